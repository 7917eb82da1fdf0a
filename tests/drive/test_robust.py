"""Robustness of the sensorless drive and of the injection compensator.

One test per class of operating point where the drive or the compensator can fail (load steps,
ramps, low speed, detuning), each at a point chosen here, asserting the required behaviour.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from data.first_release import first_release

from imdrive.cli import EXIT_LOST_CONTROL, main
from imdrive.config.perunit import resolve
from imdrive.config.scenario import Scenario
from imdrive.run.batch import simulate_batch
from imdrive.run.metrics import drive_metrics, lost_control_time
from imdrive.run.simulate import simulate

# ------------------------------------------------------------------------------------------
# finding 2: loss of control is a result


def test_lost_control_time_definition():
    t = np.arange(0.0, 3.0, 0.1)
    ref = np.zeros_like(t)
    sp = np.where((t > 0.45) & (t < 0.95), 500.0, 0.0)  # 0.5 s out: too short
    sp = np.where(t > 1.45, 500.0, sp)  # from 1.5 s to the end (1.4 s): lost
    assert lost_control_time(t, sp, ref, 200.0, 1.0) == pytest.approx(1.5)
    assert math.isnan(lost_control_time(t, sp, ref, 200.0, 2.0))
    assert math.isnan(lost_control_time(t, sp, ref, 0.0, 1.0))  # off


def _runaway():
    # rated regenerating load at 40 rpm: inside the low-speed regenerating region where
    # Schauder's MRAS has no stable equilibrium (docs/stability.md); the drive runs away (the
    # rotated error, mras.regeneration_angle_deg, the default, holds it: pinned off here)
    return Scenario.read(
        "sensorless",
        [
            "control.speed_ref_rpm={initial=0,changes=[{at=0.5,to=40,over=0.2}]}",
            "load.torque_Nm={initial=0,changes=[{at=1.0,to=-12,over=0.2}]}",
            "simulation.t_end_s=4.0",
            "mras.regeneration_angle_deg=0",
        ],
    )


@pytest.mark.slow  # 1.5 s or more on 2 cores (2.1-3.2 s measured 2026-11-29)
def test_runaway_is_flagged_in_result_summary_batch_and_cli(tmp_path):
    sc = _runaway()
    res = simulate(sc)
    assert not res.diverged
    assert res.lost_control
    assert 1.0 < res.lost_control_at_s < 3.0
    m = drive_metrics(res)
    assert m["lost_control"] and m["lost_control_at_s"] == res.lost_control_at_s
    nominal = Scenario.read("sensorless")
    b = simulate_batch([sc, nominal]).metrics
    assert list(b["lost_control"]) == [True, False]
    # full-rate batch against the decimated log: the same departure, to a log period
    assert b["lost_control_at_s"][0] == pytest.approx(res.lost_control_at_s, abs=2e-3)
    assert math.isnan(b["lost_control_at_s"][1])
    out = tmp_path / "run"
    code = main(
        [
            "run",
            "sensorless",
            "--quiet",
            "--out",
            str(out),
            "--set",
            "control.speed_ref_rpm={initial=0,changes=[{at=0.5,to=40,over=0.2}]}",
            "--set",
            "load.torque_Nm={initial=0,changes=[{at=1.0,to=-12,over=0.2}]}",
            "--set",
            "simulation.t_end_s=4.0",
            "--set",
            "output.figures=false",
            "--set",
            "output.csv=false",
            "--set",
            "mras.regeneration_angle_deg=0",
        ]
    )
    assert code == EXIT_LOST_CONTROL == 3
    s = json.loads((out / "summary.json").read_text())
    assert s["lost_control"] is True and s["diverged"] is False
    assert s["lost_control_at_s"] == pytest.approx(res.lost_control_at_s)


# ------------------------------------------------------------------------------------------
# finding 1: robust default tuning of the MRAS (docs/stability.md, "Default tuning")


@pytest.mark.slow  # end to end: closed-loop runs of seconds
def test_default_tuning_is_stable_over_the_R1_range():
    """The maps: stable for R1_hat/R1 in [0.85, 1.15] at 150-1500 rpm, rated motoring load."""
    from imdrive.config.mras_bandwidth import mras_bandwidth_Hz
    from imdrive.stability import stability_map

    sc = Scenario.read("sensorless")
    assert (sc.mras.wc_rad_s, mras_bandwidth_Hz(sc)) == (15.0, 20.0)
    speeds = np.arange(150.0, 1501.0, 90.0)
    for r in (0.85, 1.15):
        df = stability_map(sc, speeds, [12.0], R1_ratio=r)
        assert df.stable.all(), (r, df[~df.stable])
    # the paper tuning (wc = 5 rad/s, 40 Hz) is not (its limit: 1.05 at 1500 rpm)
    old = Scenario.read("sensorless", ["mras.wc_rad_s=5", "mras.bandwidth_Hz=40"])
    assert not stability_map(old, speeds, [12.0], R1_ratio=1.1).stable.all()


def test_no_limit_cycle_with_overestimated_R1():
    """R1_hat = 1.1 R1 at 1250 rpm, 9 N m: the default tuning holds the speed, no limit cycle."""
    sc = Scenario.read(
        "sensorless",
        [
            "control.speed_ref_rpm={initial=0,changes=[{at=0.5,to=1250,over=1.0}]}",
            "load.torque_Nm={initial=0,changes=[{at=2.0,to=9}]}",
            "estimator.R1_ohm=" + repr(1.1 * Scenario.read("sensorless").machine.R1_ohm),
            "simulation.t_end_s=5.0",
        ],
    )
    m = drive_metrics(simulate(sc), window_s=1.0)
    assert not m["lost_control"]
    assert m["speed_ripple_rpm"] < 1.0
    # the steady-state error an R1 error costs (no R2 error here): small, no oscillation
    assert abs(m["speed_error_rpm"]) < 2.0


# ------------------------------------------------------------------------------------------
# finding 3: the blind band near the injection frequency (gating, frequency schedule)


def _injection_at(speed, torque, ratio, t_end=16.0, extra=()):
    R2 = Scenario.read("injection-fig5").machine.R2_ohm
    return first_release(
        "injection-fig5",
        [
            f"control.speed_ref_rpm={{initial=0,changes=[{{at=0.5,to={speed},over=1.0}}]}}",
            f"load.torque_Nm={{initial=0,changes=[{{at=2.0,to={torque}}}]}}",
            f"estimator.R2_ohm={ratio * R2}",
            "compensator.R2_min_ohm=0.3",
            "compensator.R2_max_ohm=1.5",
            f"simulation.t_end_s={t_end}",
            *extra,
        ],
    )


def test_convergence_with_the_stator_frequency_at_the_injection_frequency():
    """54 rpm, 1.5 N m: f_e = 2.1 Hz, at the 2 Hz injection. Without the schedule R2_hat froze
    12.6 % off (measured); with it the injection moves to 4 Hz and R2_hat converges."""
    res = simulate(_injection_at(54, 1.5, 1.15))
    m = drive_metrics(res)
    assert abs(m["R2_error_pct"]) < 1.0
    assert abs(m["speed_error_rpm"]) < 0.5
    assert np.any(res["inj_freq_Hz"] == 4.0)  # the switch is logged
    assert np.any(res["comp_frozen_flags"].astype(int) & 8)
    off = simulate(_injection_at(54, 1.5, 1.15, extra=("compensator.gating=false",)))
    assert abs(drive_metrics(off)["R2_error_pct"]) > 5.0  # the finding, reproduced


# ------------------------------------------------------------------------------------------
# finding 7: faster, finer adaptation (the model-based law, compensator.step_law = "kalman")


def _r2_ramp(extra=()):
    return first_release(
        "injection-fig5-150rpm",
        [
            "estimator.R2_ohm=0.816",
            "plant.R2_scale={initial=1,changes=[{at=8,to=1.3,over=5}]}",
            "simulation.t_end_s=19",
            *extra,
        ],
    )


def test_the_model_based_law_follows_a_ramp_and_removes_the_quantisation():
    """+30 % of R2 within 5 s at 150 rpm (6 %/s, 230 times rated rotor heating): the published
    steps lag by 8 % and end 0.45 % off. The Kalman law told R2 may drift this fast
    (``kalman.drift_pu`` 0.1) lags 5.3 % (one 0.5 s window and the filter) and ends 0.05 %
    off: no quantisation. (Its default 0.02, tuned for thermal drift, lags 7.0 % and ends
    0.9 % off; the adaptive law of earlier releases, deciding every half window, lagged under
    3 %.)"""

    def lag(res):
        s = res.signals
        rel = 100 * (s["R2_hat_ohm"] - s["R2_ohm"]) / s["R2_ohm"]
        t = s["time_s"]
        return np.abs(rel[t >= 6]).max(), np.abs(rel[t >= 17]).max()

    table_lag, table_end = lag(simulate(_r2_ramp()))
    assert table_lag > 6.0 and table_end > 0.3  # the finding, reproduced
    kf_lag, kf_end = lag(
        simulate(_r2_ramp(('compensator.step_law="kalman"', "kalman.drift_pu=0.1")))
    )
    assert kf_lag < 0.75 * table_lag
    assert kf_end < 0.1


# ------------------------------------------------------------------------------------------
# finding 6: online R1 estimation beside the MRAS (mras.R1_rate_per_s)

_R1_ON = ('compensator.step_law="kalman"', "mras.R1_rate_per_s=0.3")


def test_online_R1_removes_the_R2_bias_of_an_R1_error():
    """150 rpm, rated load, R1_hat = 0.9 R1: R2_hat is biased and the speed error is ~3 rpm;
    with the R1 estimation both are gone."""
    R1 = Scenario.read("injection-fig5-150rpm").machine.R1_ohm

    def run(extra):
        sc = first_release(
            "injection-fig5-150rpm",
            [f"estimator.R1_ohm={0.9 * R1}", "simulation.t_end_s=16", *extra],
        )
        res = simulate(sc)
        return drive_metrics(res), res["R1_hat_ohm"][-1] / res["R1_ohm"][-1]

    m0, _ = run(('compensator.step_law="kalman"',))
    assert abs(m0["speed_error_rpm"]) > 2.0 and abs(m0["R2_error_pct"]) > 0.8
    m1, r1 = run(_R1_ON)
    assert abs(r1 - 1.0) < 0.005
    assert abs(m1["R2_error_pct"]) < 0.2
    assert abs(m1["speed_error_rpm"]) < 0.1


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_thermal_model_at_150_rpm_speed_error_under_1_rpm():
    """R1 and R2 heat together (+13-15 % in 40 s, thermal time constants shortened to 15 s)."""

    def run(extra):
        sc = first_release(
            "injection-fig5-150rpm",
            [
                "estimator.R2_ohm=0.816",
                "plant.thermal.enabled=true",
                "plant.thermal.tau1_s=15",
                "plant.thermal.tau2_s=15",
                "simulation.t_end_s=40",
                *extra,
            ],
        )
        res = simulate(sc)
        t = res["time_s"]
        err = (res["speed_rpm"] - res["speed_ref_rpm"])[t >= 8]
        n = int(round(0.5 / (t[1] - t[0])))  # 0.5 s means: the injection ripple out
        return np.abs(err[: len(err) // n * n].reshape(-1, n).mean(axis=1)).max()

    assert run(()) > 3.0  # the finding, reproduced
    assert run(_R1_ON) < 1.0


# ------------------------------------------------------------------------------------------
# finding 5: transients after convergence (gating, with the model-based law)


def test_R2_hat_holds_through_a_speed_step_a_load_cycle_and_a_fast_ramp():
    """Converged at 1000 rpm, then 1000 -> 500 rpm step (10 s), rated load removed (13 s) and
    re-applied (16 s), 500 -> 1000 rpm in 0.5 s (19 s). Ungated, R2_hat left by 21-30 %."""
    sc = first_release(
        "injection-fig5",
        [
            "control.speed_ref_rpm={initial=0,changes=[{at=0.5,to=1000,over=1.0},"
            "{at=10,to=500},{at=19,to=1000,over=0.5}]}",
            "load.torque_Nm={initial=0,changes=[{at=2,to=12},{at=13,to=0},{at=16,to=12}]}",
            'compensator.step_law="kalman"',
            "simulation.t_end_s=24",
        ],
    )
    res = simulate(sc)
    assert not res.lost_control and not res.diverged
    t = res["time_s"]
    rel = np.abs(res["R2_hat_ohm"] - res["R2_ohm"]) / res["R2_ohm"]
    assert rel[t >= 8].max() < 0.05
    assert rel[-1] < 0.002
    err = (res["speed_rpm"] - res["speed_ref_rpm"])[t >= 22]
    assert np.abs(err).max() < 1.0  # the fast ramp followed, settled 2.5 s after it
    assert np.any(res["comp_frozen_flags"][t >= 8].astype(int) & 3)  # the gating acted


# ------------------------------------------------------------------------------------------
# item 4: voltage headroom of the injection, field weakening


def test_field_weakening_holds_the_voltage_and_freezes_the_compensator():
    """Converged at 1000 rpm, then 2000 rpm (above base speed), 6 N m. Without field
    weakening the voltage saturates; with it the flux falls, the voltage stays at 0.9 of the
    limit, the injection is off and R2_hat is held (frozen, flag 32)."""

    def run(extra):
        sc = first_release(
            "injection-fig5",
            [
                "control.speed_ref_rpm={initial=0,changes=[{at=0.5,to=1000,over=1.0},"
                "{at=10,to=2000,over=2.0}]}",
                "load.torque_Nm={initial=0,changes=[{at=3,to=6}]}",
                'compensator.step_law="kalman"',
                "simulation.t_end_s=18",
                *extra,
            ],
        )
        res = simulate(sc)
        t = res["time_s"]
        v = np.hypot(res["v_ref_alpha_V"], res["v_ref_beta_V"]) / sc.inverter.v_max_V
        return res, t, v

    res, t, v = run(())
    assert v[t >= 14].max() > 0.99  # saturated
    res, t, v = run(("control.field_weakening=true",))
    assert not res.lost_control
    late = t >= 14
    assert v[late].max() < 0.97 and v[late].mean() < 0.94
    assert res["id_ref_A"][late].mean() < 0.85 * res["id_ref_A"][t < 9.9][-1]
    assert np.ptp(res["id_ref_A"][late]) < 0.05  # the injection is off
    assert np.all(res["comp_frozen_flags"][late].astype(int) & 32)
    r2_before = res["R2_hat_ohm"][t < 9.9][-1]
    assert np.ptp(res["R2_hat_ohm"][late]) == 0.0  # held
    assert res["R2_hat_ohm"][-1] == pytest.approx(r2_before, rel=5e-3)
    assert abs(r2_before / res["R2_ohm"][-1] - 1.0) < 0.01


# ------------------------------------------------------------------------------------------
# item 8: the envelope sweep (docs/envelope.md); the sweep itself takes ~80 s, not run here


def test_envelope_sweep_preset():
    from imdrive.sweep.spec import load_sweep, sweep_names

    assert "envelope" in sweep_names()
    sw = load_sweep("envelope")
    assert [a.name for a in sw.axes] == ["speed_rpm", "load_Nm", "R2_ratio", "R1_ratio", "variant"]
    assert min(sw.axes[1].values) < 0 < max(sw.axes[1].values)  # regenerating and motoring
    inj = sw.scenario_for((150, -6, 1.2, 0.9, "injection"))
    assert inj.compensator.step_law == "kalman" and inj.mras.R1_rate_per_s > 0
    assert inj.mras.R1_standstill
    assert (resolve(inj).inj_f3, resolve(inj).gate_band) == (6.0, 1.5)  # the defaults
    assert resolve(inj).R1_hat == pytest.approx(0.9 * inj.machine.R1_ohm)
    assert resolve(inj).R2_hat == pytest.approx(1.2 * inj.machine.R2_ohm)
    plain = sw.scenario_for((150, -6, 1.0, 1.0, "uncompensated"))
    assert not plain.compensator.enabled and plain.mras.R1_rate_per_s == 0
