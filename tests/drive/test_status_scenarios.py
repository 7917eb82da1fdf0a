"""No unflagged failures: deliberately failing drives on two machines of the library each carry
a status that says why, and good drives report ok (imdrive.run.status).

Failing, on today's code (measured on both machines, 2026-11-23):

* ``frozen-high-speed``: injection-robust without its estimation headroom and thermal model
  (``injection.headroom_voltage`` unset, ``compensator.thermal_model = false``: the preset as
  it was before them; with them it converges there) at 96 % of the rated
  speed (1650 rpm on Table IV) from R2_hat(0) = 1.25 R2: the injection backs off for voltage
  headroom, the compensator never updates (R2_hat stays 25 % off, the speed 23 rpm off);
* ``low-bandwidth``: the sensorless drive with a 0.3 Hz speed loop: the rated-load step
  pulls the speed away (lost control);
* ``detuned-uncompensated``: the sensorless drive with R2_hat = 1.2 R2 and no compensator
  (R2_hat 20 % off, the speed 0.2 rated slips off);
* ``R2-swing``: the sensorless drive with exact resistances whose plant R2 rises 5 % for
  0.15 s inside the final window and returns: R2_hat ends exact, but was 4.8 % off within the
  window (``R2-unsettled``, the verdict of an R2_hat that swings and ends right by phase).

Good: injection-robust at 58 % of the rated speed and rated load (R2_hat from 1.2 R2 ends
within 0.03 %; held only while the injection starts, 10 % of the compensator's time), and
the sensorless drive with exact resistances. Plus one whose outcome is not prescribed:
injection-robust on a switching bridge with 2 us dead time compensated with a 20 % error,
regenerating at 30 % of the rated torque (the dead-time bias of the detection);
whatever it ends at, its verdict must agree with its numbers.
"""

from __future__ import annotations

import math

import pytest

from imdrive.config.rated import rated_point
from imdrive.config.scenario import Scenario
from imdrive.run.batch import simulate_batch
from imdrive.run.diagnosis import closing_line

MACHINES = ("paper-table-iv", "krause-3hp")
BRIDGE = [
    'inverter.model="switching"',
    "inverter.dead_time_s=2e-6",
    'control.dead_time_compensation="feedforward"',
    "control.dead_time_compensation_s=1.6e-6",
]


def _profile(v0, at, v1, over=None) -> str:
    o = f", over = {over}" if over else ""
    return f"{{ initial = {v0}, changes = [{{ at = {at}, to = {v1}{o} }}] }}"


#: the plant's R2 5 % up over 0.15 s of the final 0.5 s window, back to where it started, so
#: an exact R2_hat ends right but was 4.8 % off inside the window
SWING = (
    "plant.R2_scale={ initial = 1.0, changes = [{ at = 3.7, to = 1.05 }, { at = 3.85, to = 1.0 }] }"
)


def _cases():
    out = []
    for m in MACHINES:
        rp = rated_point(Scenario.read("injection-robust", [f"machine.preset={m}"]).machine)

        def ov(speed_pu, load_pu, *extra, m=m, rp=rp):
            return [
                f"machine.preset={m}",
                f"control.speed_ref_rpm={_profile(0, 0.5, speed_pu * rp.speed_rpm, 1.0)}",
                f"load.torque_Nm={_profile(0, 2.0, load_pu * rp.torque_Nm)}",
                *extra,
            ]

        out += [
            (m, "good-injection", "injection-robust", ov(0.58, 1.0)),
            (m, "good-sensorless", "sensorless",
             ov(0.5, 0.5, "estimator.R2_ratio=1.0", "simulation.t_end_s=6")),
            (m, "frozen-high-speed", "injection-robust",
             ov(0.96, 1.0, "estimator.R2_ratio=1.25", "compensator.thermal_model=false")),
            (m, "low-bandwidth", "sensorless",
             ov(0.5, 1.0, "control.speed_bandwidth_Hz=0.3", "simulation.t_end_s=4")),
            (m, "detuned-uncompensated", "sensorless",
             ov(0.5, 1.0, "estimator.R2_ratio=1.2", "simulation.t_end_s=6")),
            (m, "dead-time-regenerating", "injection-robust",
             ov(0.58, -0.3, "estimator.R2_ratio=1.0", *BRIDGE)),
            (m, "R2-swing", "sensorless",
             ov(0.5, 0.5, "estimator.R2_ratio=1.0", "simulation.t_end_s=4", SWING)),
        ]  # fmt: skip
    return out


CASES = _cases()


def _read(name: str, preset: str, overrides: list) -> Scenario:
    sc = Scenario.read(preset, overrides)
    if name != "frozen-high-speed":
        return sc
    d = sc.to_dict()  # a key cannot be unset by an override: through the scenario's table
    d["injection"]["headroom_voltage"] = None
    return Scenario.from_dict(d)


@pytest.fixture(scope="module")
def runs():
    scs = [_read(name, preset, o) for _, name, preset, o in CASES]
    res = simulate_batch(scs, logs=True)
    return {(m, name): (row, r) for (m, name, _, _), (_, row), r in
            zip(CASES, res.metrics.iterrows(), res.results, strict=True)}  # fmt: skip


def _failed(row) -> bool:
    """The run's numbers say it is not fine (the issue's rule, and an R2_hat that was outside
    the status's tolerance within the final window)."""
    return (
        bool(row["lost_control"])
        or bool(row["diverged"])
        or not abs(row["R2_error_pct"]) <= 5.0
        or not abs(row["R2_error_window_pct"]) <= 2.0
        or not abs(row["speed_error_rpm"]) <= row["speed_tolerance_rpm"]
    )


pytestmark = pytest.mark.slow  # end to end: 12 closed-loop runs of 4-14 s


@pytest.mark.parametrize("machine", MACHINES)
def test_no_failing_run_reports_itself_ok(runs, machine):
    for (m, name), (row, res) in runs.items():
        if m != machine:
            continue
        if _failed(row):
            assert row["verdict"] != "ok" and not row["verdict_ok"], (name, row["verdict_text"])
            assert closing_line(res), name  # the console names it
        else:
            assert row["verdict"] == "ok", (name, row["verdict_text"])
        # the logged run (decimated) tells the same story as the batch's full-rate row
        assert res.verdict["verdict"] == row["verdict"], name


@pytest.mark.parametrize("machine", MACHINES)
def test_each_failure_says_why(runs, machine):
    row, res = runs[(machine, "frozen-high-speed")]
    assert row["verdict"] == "frozen" and row["R2_error_pct"] == pytest.approx(25.0)
    assert "voltage limit" in row["verdict_text"] and "R2 never estimated" in row["verdict_text"]
    assert row["R2_held_pct"] > 90.0
    line = closing_line(res)
    assert line.startswith("compensator frozen from t = 4.")  # the first cause, in time order
    assert res.verdict["R2_observable"].startswith("not observable here: held since t = 4.")
    assert "voltage limit" in res.verdict["R2_observable"]

    row, res = runs[(machine, "low-bandwidth")]
    assert row["verdict"] == "lost-control" and row["lost_control"]
    assert row["verdict_text"].startswith(f"lost control at t = {row['lost_control_at_s']:.3g} s")
    assert closing_line(res).startswith("lost control at t =")

    row, _ = runs[(machine, "detuned-uncompensated")]
    assert row["verdict"] == "R2-off"
    assert row["verdict_text"].startswith("R2_hat off by +20 % (compensator off)")
    assert "speed error" in row["verdict_text"]
    assert 0.1 < row["speed_error_pu_slip"] < 0.3  # 0.2 rated slips: the detuning law

    row, _ = runs[(machine, "dead-time-regenerating")]
    if abs(row["R2_error_pct"]) > 2.0:
        assert "R2_hat off by" in row["verdict_text"]


@pytest.mark.parametrize("machine", MACHINES)
def test_an_R2_hat_right_only_at_its_last_sample_is_not_settled(runs, machine):
    row, res = runs[(machine, "R2-swing")]
    assert abs(row["R2_error_pct"]) < 1e-9  # ends exact, as the plant returned to R2(0)
    assert row["R2_error_window_pct"] == pytest.approx(100 * (1 / 1.05 - 1), rel=1e-9)
    assert row["verdict"] == "R2-unsettled" and not row["verdict_ok"]
    assert row["verdict_text"].startswith("R2_hat not settled: -4.76 % off within the final")
    assert closing_line(res).startswith("R2_hat not settled")
    assert res.verdict["verdict"] == "R2-unsettled"  # the decimated log sees the step too


@pytest.mark.parametrize("machine", MACHINES)
def test_good_runs_report_ok(runs, machine):
    for name in ("good-injection", "good-sensorless"):
        row, res = runs[(machine, name)]
        assert row["verdict"] == "ok" and row["verdict_ok"], (name, row["verdict_text"])
        assert abs(row["R2_error_pct"]) < 2.0
        assert closing_line(res) is None
    row, res = runs[(machine, "good-injection")]
    # estimated throughout but while the injection starts: its first decision periods are
    # gated by design (flag 8), measured 10.0 % of the compensator's time on both machines
    assert row["R2_held_pct"] <= 10.0 + 1e-9
    assert res.verdict["R2_observable"] == "estimated at the end"
    assert math.isnan(row["R2_held_since_s"])
