"""Sweeps: the file format, local and dask execution, the resumable store, bad input."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from data.first_release import first_release
from data.inprocess import imdrive_here

from imdrive.config.perunit import resolve
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.run.simulate import simulate
from imdrive.sweep import _apply, load_sweep, parse_sweep, run_sweep, sweep_names

R2 = 0.816

# 3 x 2 x 2 = 12 short runs; "unstable" diverges at once (negative current gain, huge DC link)
SMALL = """
name = "small"
base = "sensorless"
chunk_size = 5
window_s = 0.1

[set]
simulation.t_end_s = 0.4
control.speed_ref_rpm = { initial = 0, changes = [{ at = 0.05, to = 600, over = 0.15 }] }
load.torque_Nm = { initial = 0, changes = [{ at = 0.25, to = 6 }] }

[axes]
R2_ratio = { min = 0.8, max = 1.2, num = 3 }
speed_rpm = [300, 900]

[axes.variant]
stable = {}
unstable = { control.current_kp = 150, "inverter.Vdc_V" = 1e5 }

[[heatmap]]
x = "R2_ratio"
y = "speed_rpm"
value = "speed_error_rpm"
rows = "variant"
"""


def _imdrive(*args, timeout=300, **kw):
    return subprocess.run(
        [sys.executable, "-m", "imdrive", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=timeout,
        **kw,
    )


@pytest.fixture(scope="module")
def small_file(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("sweepfile") / "small.toml"
    p.write_text(SMALL)
    return p


@pytest.fixture(scope="module")
def local_run(small_file, tmp_path_factory):
    out = tmp_path_factory.mktemp("local") / "store"
    sweep = load_sweep(str(small_file))
    return sweep, out, run_sweep(sweep, out, progress=False)


# ------------------------------------------------------------------------------------------
# format


def test_grid_runs_are_the_product_last_axis_fastest(small_file):
    sw = load_sweep(str(small_file))
    assert sw.n_runs == 12 and sw.shape == (3, 2, 2) and not sw.random
    assert sw.run_values(0) == (0.8, 300, "stable")
    assert sw.run_values(1) == (0.8, 300, "unstable")
    assert sw.run_values(2) == (0.8, 900, "stable")
    assert sw.run_values(11) == (1.2, 900, "unstable")
    sc = sw.scenario(7)  # R2_ratio 1.0, 900 rpm, unstable
    assert sc.estimator.R2_ratio == 1.0 and resolve(sc).R2_hat == pytest.approx(R2)
    assert sc.control.speed_ref_rpm.points[-1] == (0.2, 900.0)
    assert sc.control.speed_ref_rpm.points[:-1] == ((0.0, 0.0), (0.05, 0.0))
    assert sc.control.current_kp == 150.0 and sc.inverter.Vdc_V == 1e5
    assert sc.simulation.t_end_s == 0.4


def test_run_scenarios_equal_scenario_read_with_the_same_overrides(small_file):
    sw = load_sweep(str(small_file))
    ov = [
        "simulation.t_end_s=0.4",
        "control.speed_ref_rpm={ initial = 0, changes = [{ at = 0.05, to = 900, over = 0.15 }] }",
        "load.torque_Nm={ initial = 0, changes = [{ at = 0.25, to = 6 }] }",
        "estimator.R2_ratio=1.2",  # the R2_ratio axis: a ratio of the run's machine's R2
    ]
    assert sw.scenario(10) == Scenario.read("sensorless", ov)
    # the fast path for key paths (dataclasses.replace) equals the TOML-dict path
    base = Scenario.read("sensorless")
    for key, value, text in [
        (("mras", "bandwidth_Hz"), 25, "25"),
        (("machine", "J_kgm2"), 0.1, "0.1"),
        (("plant", "thermal", "enabled"), True, "true"),
        (("control", "flux_ref_Wb"), 0.6, "0.6"),
        (("compensator", "table"), "rules", '"rules"'),
    ]:
        assert _apply(base, key, value) == Scenario.read("sensorless", [f"{'.'.join(key)}={text}"])


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_random_sweep_is_reproducible_and_inside_the_ranges(tmp_path):
    text = """
base = "sensorless"
samples = 50
seed = 3
[axes]
R2_ratio = { min = 0.6, max = 1.4 }
"mras.bandwidth_Hz" = [20, 40, 80]
"""
    a = parse_sweep(text)
    b = parse_sweep(text)
    c = parse_sweep(text.replace("seed = 3", "seed = 4"))
    assert a.n_runs == 50 and a.random
    assert a.axes == b.axes and a.fingerprint() == b.fingerprint()
    assert a.axes[0].values != c.axes[0].values
    r = np.array(a.axes[0].values)
    assert r.min() >= 0.6 and r.max() <= 1.4 and len(set(r)) == 50
    assert set(a.axes[1].values) == {20, 40, 80}


def _comp_record(sc, without=()) -> dict:
    """The compensator's and injection's parameters the kernels receive (but the MRAS's
    filter cut-off the detection's decoupling reads: the map keeps the sensorless drive's),
    less the fields ``without``."""
    from imdrive.run.build import build_arrays

    rec = build_arrays(sc).params.comp[0]
    skip = {"cpl_wc", *without}
    return {f: rec[f].item() for f in rec.dtype.names if f not in skip}


def test_step_ranges_and_preset_sweep():
    sw = parse_sweep(
        'base = "sensorless"\n[axes]\nspeed_rpm = { min = 100, max = 1000, step = 300 }'
    )
    assert sw.axes[0].values == (100.0, 400.0, 700.0, 1000.0)
    assert "detuning-map" in sweep_names()
    dm = load_sweep("detuning-map")
    assert [a.name for a in dm.axes] == ["R2_ratio", "speed_rpm", "load_Nm", "variant"]
    assert dm.axes[0].values[0] == 0.6 and dm.axes[0].values[-1] == 1.4
    assert min(dm.axes[1].values) == 50 and max(dm.axes[1].values) == 1500
    assert dm.axes[2].values[0] == 0 and dm.axes[2].values[-1] == 12
    assert dm.axes[3].values == ("uncompensated", "paper", "injection")
    # the variants carry the compensation presets' settings
    paper = dm.scenario_for((1.2, 1000, 12.0, "paper"))
    inj = dm.scenario_for((1.2, 1000, 12.0, "injection"))
    plain = dm.scenario_for((1.0, 50, 0.0, "uncompensated"))
    ref_p = Scenario.read("paper-fig5")
    # the map was measured with the injection presets' first-release tuning
    ref_i = first_release("injection-fig5")
    # the same records but the clamps, and the injection's step in per-unit of R2_hat(0):
    # the map states none of them in ohm (deprecated spellings), and its clamps are the
    # defaults, 0.5 and 2 R2_hat(0), so that no start on its axis (0.6 ... 1.4 R2) has a
    # clamp at or short of R2 (the presets' 1.25 R2_hat(0) is R2 itself from 0.8 R2)
    clamps = ("R2_min", "R2_max")
    assert _comp_record(paper, clamps) == _comp_record(ref_p, clamps)
    R2_hat0 = resolve(paper).R2_hat
    assert R2_hat0 == pytest.approx(ref_p.estimator.R2_ohm, rel=1e-15)
    for sc in (paper, inj):
        rec = _comp_record(sc)
        assert (rec["R2_min"], rec["R2_max"]) == pytest.approx((0.5 * R2_hat0, 2.0 * R2_hat0))
    assert _comp_record(inj, (*clamps, "G_CR")) == _comp_record(ref_i, (*clamps, "G_CR"))
    # its step: the first release's 0.02 ohm at R2_hat(0) = R2, in per-unit of R2_hat(0)
    assert _comp_record(inj)["G_CR"] == pytest.approx(0.02 * R2_hat0 / resolve(plain).R2_hat)
    assert paper.control == ref_p.control and paper.load == ref_p.load
    assert not plain.compensator.enabled and resolve(plain).inj_amp == 0


# ------------------------------------------------------------------------------------------
# running


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_local_sweep_table_matches_single_runs(local_run):
    sweep, out, df = local_run
    assert list(df["run"]) == list(range(12))
    assert (out / "runs.parquet").is_file()
    pd.testing.assert_frame_equal(pd.read_parquet(out / "runs.parquet"), df)
    assert len(list((out / "chunks").glob("chunk-*.parquet"))) == 3
    man = json.loads((out / "manifest.json").read_text())
    assert man["complete"] and man["n_runs"] == 12 and man["completed_chunks"] == [0, 1, 2]
    assert list((out / "figures").glob("*.png"))
    # the diverging runs are recorded, the others complete
    unstable = df["variant"] == "unstable"
    assert df.loc[unstable, "diverged"].all()
    assert (df.loc[unstable, "diverged_at_s"] < 0.4).all()
    assert not df.loc[~unstable, "diverged"].any()
    assert np.isfinite(df.loc[~unstable, "speed_error_rpm"]).all()
    # a row is the run's single simulation
    row = df.iloc[10]
    res = simulate(sweep.scenario(10))
    # the sweep's window, the last 0.1 s of the run (t >= 0.3 s while the run ended at
    # t_end_s = 0.4 s; the premagnetisation's delay ends it at 0.5684 s: the mean over
    # t >= 0.3 s was -36.34 rpm, the row's -33.25, the last 0.1 s logged -33.21)
    from imdrive.config.sequence import sequence

    w = res.window(sequence(res.scenario).t_end_s - 0.1)
    # the run's end, not its last logged row: the premagnetisation (3 T2_hat = 0.218 s against
    # the profile's 0.05 s) delays the duty cycle and the end by 0.1684 s, so the run's
    # 5684 periods end 4 periods after the last row logged every 10 (768.04 rpm there, the
    # speed still rising along the torque-limited ramp; 769.13 rpm at the end in both)
    assert row["final_speed_rpm"] == pytest.approx(res.final_values()["speed_rpm"], rel=1e-12)
    assert row["R2_hat_final_ohm"] == pytest.approx(1.2 * R2)
    assert row["speed_error_rpm"] == pytest.approx(
        np.mean(w["speed_rpm"] - w["speed_ref_rpm"]), abs=0.5
    )


@pytest.mark.slow
def test_dask_cluster_gives_the_same_table(local_run, tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    sweep, _, df = local_run
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        remote = run_sweep(
            sweep, tmp_path / "dask", scheduler=cluster.scheduler_address, figures=False
        )
    pd.testing.assert_frame_equal(remote, df)


@pytest.mark.slow
def test_killed_sweep_resumes_without_loss_or_duplicates(tmp_path, local_run):
    # slow runs (many RK4 sub-steps) so that the kill lands mid-way
    text = SMALL.replace("chunk_size = 5", "chunk_size = 1").replace(
        "simulation.t_end_s = 0.4", "simulation.t_end_s = 0.4\nsimulation.substeps = 60"
    )
    f = tmp_path / "slow.toml"
    f.write_text(text)
    store = tmp_path / "store"
    proc = subprocess.Popen(
        [sys.executable, "-m", "imdrive", "sweep", str(f), "--out", str(store), "-q"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    chunks = store / "chunks"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if chunks.is_dir() and len(list(chunks.glob("chunk-*.parquet"))) >= 2:
            break
        time.sleep(0.005)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    done = len(list(chunks.glob("chunk-*.parquet")))
    assert proc.returncode == -signal.SIGKILL
    assert 2 <= done < 12, "the kill must land mid-way"
    assert not (store / "runs.parquet").exists()
    # without --resume the store is not touched (the next commands through main() in this
    # process: only the killed one needs a process of its own)
    again = imdrive_here("sweep", f, "--out", store, "-q", cwd=tmp_path)
    assert again.returncode == 2 and "--resume" in again.stderr
    assert len(list(chunks.glob("chunk-*.parquet"))) == done
    resumed = imdrive_here("sweep", f, "--out", store, "--resume", "-q", cwd=tmp_path)
    assert resumed.returncode == 0, resumed.stderr
    df = pd.read_parquet(store / "runs.parquet")
    assert sorted(df["run"]) == list(range(12))
    assert not list(store.rglob(".*tmp-*"))
    # identical to an uninterrupted sweep
    full = run_sweep(load_sweep(str(f)), tmp_path / "full", progress=False, figures=False)
    pd.testing.assert_frame_equal(df, full)


# ------------------------------------------------------------------------------------------
# bad input


BAD = [
    ("estimator.R2_oh", '"estimator.R2_oh" = [0.8, 0.9]', "axes.estimator.R2_oh"),
    ("empty axis", "speed_rpm = []", "axes.speed_rpm"),
    ("min > max", "load_Nm = { min = 12, max = 0, num = 3 }", "axes.load_Nm.min"),
    ("bad set key", "[axes.variant]\na = { compensator.enabeld = true }", "compensator.enabeld"),
    ("rejected value", "R2_ratio = [-1.0, 1.0]", "axes.R2_ratio"),
]


def _assert_bad_sweep(proc, out: Path, field: str) -> None:
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr
    assert field in lines[0]
    assert not out.exists()


@pytest.mark.parametrize("label, axes, field", BAD, ids=[b[0] for b in BAD])
def test_bad_sweep_file_names_the_field_and_runs_nothing(tmp_path, label, axes, field):
    """Through ``main`` in this process (``data.inprocess``: a traceback is an exception, a
    warning a line of stderr); the next test runs one case through the real command."""
    f = tmp_path / "bad.toml"
    f.write_text(f'base = "sensorless"\n[axes]\n{axes}\n')
    out = tmp_path / "store"
    _assert_bad_sweep(imdrive_here("sweep", f, "--out", out, cwd=tmp_path), out, field)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_a_bad_sweep_file_through_the_real_command(tmp_path):
    _, axes, field = BAD[0]
    f = tmp_path / "bad.toml"
    f.write_text(f'base = "sensorless"\n[axes]\n{axes}\n')
    out = tmp_path / "store"
    _assert_bad_sweep(_imdrive("sweep", f, "--out", out), out, field)


def test_existing_store_needs_resume(tmp_path, small_file):
    out = tmp_path / "store"
    out.mkdir()
    (out / "something").write_text("x")
    proc = imdrive_here("sweep", small_file, "--out", out, cwd=tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "--out" in lines[0] and "--resume" in lines[0]
    assert sorted(p.name for p in out.iterdir()) == ["something"]


def test_resume_refuses_another_sweep(local_run, small_file, tmp_path):
    _, out, _ = local_run
    other = parse_sweep(SMALL.replace("num = 3", "num = 2"))
    with pytest.raises(ConfigError, match="another sweep"):
        run_sweep(other, out, resume=True)
    with pytest.raises(ConfigError, match="chunk"):
        run_sweep(load_sweep(str(small_file)), out, resume=True, chunk_size=4)


def test_progress_bar_only_on_a_terminal():
    import io

    from imdrive.sweep import Progress

    quiet = io.StringIO()  # not a terminal
    p = Progress(10, "sweep x", unit="runs", stream=quiet)
    p.start(0)
    p.advance(5)
    p.close()
    assert quiet.getvalue() == ""
    tty = io.StringIO()
    p = Progress(10, "sweep x", unit="runs", enabled=True, stream=tty)
    p.start(2)
    p.advance(8)
    p.close()
    text = tty.getvalue()
    assert text.startswith("\rsweep x [") and "10/10 runs 100%" in text and text.endswith("\n")


def test_builtin_sweeps_state_no_deprecated_key():
    """Every built-in sweep builds and validates its scenarios without a configuration
    warning: none of them states a deprecated spelling (refused from imdrive 0.3) or replaces
    one of its base's settings by its other spelling."""
    from imdrive.errors import ConfigWarning

    for name in sweep_names():
        with warnings.catch_warnings():
            warnings.simplefilter("error", ConfigWarning)
            load_sweep(name)
