"""The batch engine: N drives in one compiled call give what N single simulate() calls give.

The metrics are checked against an independent numpy implementation of their definitions
(imdrive.batch's module docstring) applied to simulate()'s full-rate signals.
"""

from __future__ import annotations

import gc
import math
import tracemalloc

import numpy as np
import pandas as pd
import pytest

from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.kernels.engine import S_OK
from imdrive.run.batch import COLUMNS, METRICS, simulate_batch
from imdrive.run.metrics import drive_metrics
from imdrive.run.simulate import simulate

R2 = 0.816


def _ramp(speed: float, at: float = 0.1, over: float = 0.2) -> str:
    return f"{{ initial = 0, changes = [{{ at = {at}, to = {speed}, over = {over} }}] }}"


def _scenarios():
    """Different R2 errors, speeds, loads, lengths, profiles, compensators; one diverging."""
    common = ["simulation.log_every=1", "simulation.t_end_s=0.6"]
    specs = [
        # R2_hat/R2, speed ref, load, extra overrides
        (1.0, _ramp(1000), "3.0", []),
        (1.3, _ramp(500), "{ initial = 0, changes = [{ at = 0.3, to = 12 }] }", []),
        (0.7, "800", "6.0", ["control.speed_feedback=measured"]),
        (
            1.2,
            _ramp(300),
            "12",
            ["compensator.enabled=true", "compensator.t_on_s=0.2", "compensator.G_CR_ohm=0.01"],
        ),
        (0.9, _ramp(1200), "0", ["simulation.t_end_s=0.45", 'compensator.table="rules"']),
        (1.0, _ramp(600), "0", ["control.current_kp=150", "inverter.Vdc_V=1e5"]),  # diverges
    ]
    out = []
    for ratio, speed, load, extra in specs:
        ov = [
            *common,
            f"estimator.R2_ohm={R2 * ratio}",
            f"control.speed_ref_rpm={speed}",
            f"load.torque_Nm={load}",
            *extra,
        ]
        out.append(Scenario.read("sensorless", ov))
    return out


def reference_metrics(res, window_s: float = 0.5) -> dict:
    """The documented metrics, computed with numpy from a full-rate SimulationResult."""
    k = np.rint(res.signals["time_s"] / res.scenario.simulation.Ts_s).astype(int)
    assert np.array_equal(k, np.arange(len(k))), "needs log_every = 1"
    return drive_metrics(res, window_s)


@pytest.fixture(scope="module")
def scenarios():
    return _scenarios()


@pytest.fixture(scope="module")
def singles(scenarios):
    return [simulate(sc) for sc in scenarios]


@pytest.fixture(scope="module")
def batch(scenarios):
    return simulate_batch(scenarios, logs=True)


@pytest.mark.slow
def test_the_set_is_what_it_claims(singles):
    assert [r.diverged for r in singles] == [False] * 5 + [True]
    assert len({r.scenario.simulation.n_steps for r in singles}) == 2
    assert len({r.scenario.compensator.table for r in singles}) == 2


@pytest.mark.slow
def test_batch_logs_are_bit_identical_to_single_runs(singles, batch):
    assert list(batch.metrics.columns) == list(COLUMNS)
    assert len(batch.results) == len(singles)
    for one, many in zip(singles, batch.results, strict=True):
        assert many.status == one.status
        assert many.k_end == one.k_end
        assert list(many.signals) == list(one.signals)
        for name, v in one.signals.items():
            assert np.array_equal(many.signals[name], v), name
        assert np.array_equal(many.x_final, one.x_final)
        assert np.array_equal(many.c_final, one.c_final)


@pytest.mark.slow  # end to end: closed-loop runs of seconds
def test_batch_metrics_match_the_definitions_on_single_runs(singles, batch):
    df = batch.metrics
    for i, one in enumerate(singles):
        ref = reference_metrics(one)
        row = df.iloc[i]
        assert row["drive"] == i
        for name in ("status", "diverged"):
            assert row[name] == ref[name], (i, name)
        for name in ("diverged_at_s", "simulated_s", *METRICS):
            a, b = float(row[name]), float(ref[name])
            if math.isnan(b):
                assert math.isnan(a), (i, name, a)
            else:
                scale = max(abs(b), 1.0)
                assert abs(a - b) <= 1e-12 * scale, (i, name, a, b)


def test_metric_values_make_sense(batch):
    df = batch.metrics
    assert df.loc[0, "convergence_time_s"] == 0.0  # exact R2_hat throughout
    assert math.isnan(df.loc[1, "convergence_time_s"])  # 30 % off, never corrected
    assert df.loc[1, "R2_error_pct"] == pytest.approx(30.0)
    div = df.loc[5]
    assert div["diverged"] and div["status"] != S_OK
    assert 0 < div["diverged_at_s"] < 0.6
    assert math.isnan(div["speed_error_rpm"]) and math.isfinite(div["final_speed_rpm"])
    assert np.all(np.isfinite(df.loc[:4, list(METRICS[:4])].to_numpy()))
    assert batch.control_periods == sum(int(round(t / 1e-4)) for t in df["simulated_s"])


def test_decimated_logs_equal_simulate_at_that_rate(scenarios):
    from dataclasses import replace

    scs = [replace(sc, simulation=replace(sc.simulation, log_every=7)) for sc in scenarios]
    res = simulate_batch(scs, logs=True)
    for sc, many in zip(scs, res.results, strict=True):
        one = simulate(sc)
        for name, v in one.signals.items():
            assert np.array_equal(many.signals[name], v), name
    # an explicit log_every overrides the scenarios'
    res3 = simulate_batch(scenarios[:2], logs=True, log_every=3)
    sc3 = replace(scenarios[1], simulation=replace(scenarios[1].simulation, log_every=3))
    one = simulate(sc3)
    for name, v in one.signals.items():
        assert np.array_equal(res3.results[1].signals[name], v), name
    assert res3.results[0].time_s[1] == pytest.approx(3e-4)


def test_serial_kernel_small_blocks_and_generators_give_the_same_metrics(scenarios, batch):
    a = simulate_batch(iter(scenarios), parallel=False, block_size=2)
    assert a.results is None
    pd.testing.assert_frame_equal(a.metrics, batch.metrics)


def test_drives_of_different_lengths_share_one_kernel_call(scenarios, monkeypatch):
    """Each drive runs its own number of periods in one call over the threads: grouped by
    length, a batch whose drives' sequencing differs (premagnetisation, ramps) ran one drive
    per call, on one thread (a 10,000-drive batch 49 s, now 29 s)."""
    from imdrive.run import batch as rb

    calls = []
    kernel = rb.batch_kernel
    monkeypatch.setattr(rb, "batch_kernel", lambda *a: calls.append(a[4].n_steps) or kernel(*a))
    same = scenarios[:2] + scenarios[4:5]  # MRAS drives, 0.6 s and 0.45 s
    res = simulate_batch(same, logs=True)
    assert len(calls) == 1
    assert len(set(calls[0])) == 3  # each its own length
    for one, many in zip([simulate(sc) for sc in same], res.results, strict=True):
        assert many.k_end == one.k_end
        for name, v in one.signals.items():
            assert np.array_equal(many.signals[name], v), name


def test_empty_batch_and_bad_arguments(scenarios):
    assert len(simulate_batch([]).metrics) == 0
    with pytest.raises(ConfigError, match="log_every"):
        simulate_batch(scenarios[:1], logs=True, log_every=0)
    with pytest.raises(ConfigError, match="window_s"):
        simulate_batch(scenarios[:1], window_s=-1.0)


@pytest.mark.slow
def test_memory_per_drive_is_linear_and_under_1kB():
    """Without logs the batch keeps well under 1 kB per drive (its metrics row and status, the
    table's strings), and what it holds only while it runs does not grow with N: a fixed cost
    of the blocks in flight (one built ahead while the kernels run another, one judged)."""
    base = Scenario.read("sensorless", ["simulation.t_end_s=0.002"])

    def gen(n):
        from dataclasses import replace

        for i in range(n):
            yield replace(base, estimator=replace(base.estimator, R2_ohm=R2 * (0.8 + i * 1e-4)))

    # warm up with whole blocks and start each measure from a collected heap: the first batch
    # of a process builds caches once, and garbage left by earlier tests was collected inside
    # the measure (1211 B per drive in one run of the whole suite)
    simulate_batch(gen(400), block_size=100)
    kept, transient = {}, {}
    for n in (100, 400, 1600):
        gc.collect()
        tracemalloc.start()
        res = simulate_batch(gen(n), block_size=100)
        kept[n], peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        transient[n] = peak - kept[n]
        assert len(res.metrics) == n
        del res
    per_drive = (kept[1600] - kept[400]) / 1200
    assert per_drive < 1024, per_drive  # 612 B measured (2026-12-01)
    # 3.0 MB with one block, 3.1-5.5 MB at 400 and 1600 drives as the threads' timing has two
    # or three blocks in flight; with every drive's scenario kept to the end: 13.3 MB at 1600
    assert transient[1600] < 3 * transient[100], transient


def test_the_batch_runs_the_engine_compiled_for_run():
    """The batch kernels call the engine with ``simulate()``'s argument types: the constants
    of their call (``i = 0``, ``log_every = 1``) reached it as numba literals, a signature of
    its own, and the first batch after a warm ``imdrive run`` compiled the whole engine again."""
    from imdrive.kernels.engine import run_drive

    sc = Scenario.read("sensorless", ["simulation.t_end_s=0.01"])
    simulate(sc)
    before = set(run_drive.signatures)
    for parallel in (False, True):
        assert (simulate_batch([sc, sc], parallel=parallel).metrics["status"] == S_OK).all()
    assert set(run_drive.signatures) == before  # nothing compiled (or loaded) for the batch
