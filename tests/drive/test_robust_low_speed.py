"""Low-speed robustness: standstill R1 identification, the frequency schedule's hysteresis,
the R2 law at low stator frequency and against a large error. Operating points chosen here,
not the envelope's grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.run.metrics import drive_metrics
from imdrive.run.simulate import simulate

R1 = Scenario.read("sensorless").machine.R1_ohm
R2 = Scenario.read("sensorless").machine.R2_ohm


def _standstill(r1_ratio, r2_ratio, magnetise_s=0.5, extra=()):
    sc = Scenario.read(
        "sensorless",
        [
            "mras.R1_standstill=true",
            "mras.R1_standstill_levels=1",  # two levels: test_r1_two_levels.py
            f"estimator.R1_ohm={r1_ratio * R1}",
            f"estimator.R2_ohm={r2_ratio * R2}",
            f"control.speed_ref_rpm={{initial=0,changes=[{{at={magnetise_s},to=300,over=1}}]}}",
            f"simulation.t_end_s={magnetise_s + 0.2}",
            *extra,
        ],
    )
    res = simulate(sc)
    return res["R1_hat_ohm"][-1] / R1


@pytest.mark.parametrize("r1_ratio", [0.8, 1.15])
def test_standstill_R1_identification_with_the_right_R2(r1_ratio):
    # the build-up left is fitted as the decay at the T2 the drive measured, which leaves
    # -0.025 / -0.020 % (the controller's own build-up, exact only with R2_hat = R2, left
    # 1e-6 here and up to 1.7 % from R2_hat(0) = 0.6-1.4 R2: test_r1_standstill_window.py)
    assert _standstill(r1_ratio, 1.0) == pytest.approx(1.0, abs=3e-4)


@pytest.mark.parametrize("r2_ratio", [0.75, 1.25])
def test_standstill_R1_identification_with_an_R2_error(r2_ratio):
    # the flux build-up left in the window is fitted, not just subtracted (measured
    # -0.2 / +0.4 % at 0.8 / 1.2; subtracting the model's build-up alone gave +-1.1 %)
    assert _standstill(0.9, r2_ratio, magnetise_s=0.6) == pytest.approx(1.0, abs=0.006)


def test_standstill_R1_identification_needs_its_window():
    # magnetising for 0.3 s (< four rotor time constants + 50 ms) with a start that does not
    # wait for the window: R1_hat is left alone (the start waits by default:
    # test_r1_standstill_wait.py)
    no_wait = ("mras.R1_standstill_hold_T2=0",)
    assert _standstill(1.1, 1.0, magnetise_s=0.3, extra=no_wait) == pytest.approx(1.1, abs=1e-12)


def test_standstill_R1_identification_is_off_by_default():
    sc = Scenario.read("sensorless", [f"estimator.R1_ohm={1.1 * R1}", "simulation.t_end_s=0.7"])
    assert simulate(sc)["R1_hat_ohm"][-1] == pytest.approx(1.1 * R1, abs=1e-12)


def test_bad_R1_standstill_value_is_refused():
    with pytest.raises(ConfigError, match="mras.R1_standstill"):
        Scenario.read("sensorless", ["mras.R1_standstill=3"])


# ------------------------------------------------------------------------------------------
# the compensator at low stator frequency (the envelope's 50 rpm row failed here)


def _injection(speed, torque, r2_ratio, extra=()):
    """The envelope sweep's injection variant (Kalman law, R1 estimation, the sensorless
    preset's MRAS tuning) at a point of its class that is not on the sweep's grid."""
    from imdrive.sweep.spec import load_sweep

    sc = load_sweep("envelope").scenario_for((speed, torque, r2_ratio, 1.0, "injection"))
    return sc.with_overrides(["simulation.t_end_s=14", *extra])


def test_no_frequency_chatter_midway_between_the_injection_frequencies():
    """65 rpm, 4 N m: the stator frequency (about 2.9 Hz) lies between 2 and 4 Hz. The
    schedule decides once and keeps its choice (a switch at every decision kept the
    compensator frozen before the hysteresis), and the compensator keeps updating. (Where
    R2_hat ends here is not what this test checks: docs/envelope.md generates the low-speed
    cells' errors.)"""
    res = simulate(_injection(65, 4.0, 0.85))
    flags = res["comp_frozen_flags"].astype(int)
    t = res["time_s"]
    late = t > 7.0
    assert not np.any(flags[late] & 8)  # no switch after the first seconds
    assert np.mean(flags[late] != 0) < 0.1  # updating, not frozen


def test_the_law_converges_at_low_stator_frequency_without_a_limit_cycle():
    """45 rpm, 7 N m (f_e about 2.2 Hz): R2_hat settles. The adaptive law of earlier releases
    limit-cycled here with its default fine_gain of 2.5 (R2_hat swinging 13.6 % peak to peak)
    and needed a drift reset below 4 Hz; the Kalman law needs neither."""
    res = simulate(_injection(45, 7.0, 0.85))
    r2 = res["R2_hat_ohm"] / res["R2_ohm"] - 1.0
    t = res["time_s"]
    assert np.ptp(r2[t > 11.0]) < 0.01  # no limit cycle in the last 3 s
    assert abs(drive_metrics(res)["R2_error_pct"]) < 1.0


def test_drift_does_not_walk_R2_hat_away_against_a_large_error():
    """650 rpm, 11 N m, R2_hat(0) = 1.25 R2: the adaptive law's drift, wound up during the
    first large steps, kept walking R2_hat down while the table's level was 0 (measured
    -9.5 % at 600 rpm); the Kalman law's drift state must not."""
    res = simulate(_injection(650, 11.0, 1.25))
    assert abs(drive_metrics(res)["R2_error_pct"]) < 1.0


# ------------------------------------------------------------------------------------------
# the schedule over the injection's harmonics and the in-phase sensitivity


def test_in_phase_sensitivity_matches_a_finite_difference():
    from imdrive.kernels.compensator import in_phase_sensitivity

    T2 = 0.0868
    for f in (2.0, 4.0, 6.0):
        w = 2 * math.pi * f
        r = 1e-6  # R2_hat = R2 (1 + r): T2_hat = T2 / (1 + r)

        def in_phase(T, w=w):
            return 1.0 / (1.0 + (w * T) ** 2)

        fd = -(in_phase(T2 / (1 + r)) - in_phase(T2)) / r  # model minus plant, per r
        assert in_phase_sensitivity(w, T2) == pytest.approx(-fd, rel=1e-4)


def test_three_frequency_schedule_leaves_both_side_bands_away_from_DC():
    """160 rpm, -11 N m: the stator frequency (about 3 Hz) is 1 Hz from both 2 and 4 Hz; with
    the default band (0.75 of the first frequency, 1.5 Hz) the schedule takes the third
    harmonic, 6 Hz, and R2_hat converges. With the two-frequency schedule's band (half the
    first, 1 Hz) 2 or 4 Hz is used, a side band sits at 1 Hz, and R2_hat ends over 2 % off (4 %
    when it was measured with the two-frequency schedule)."""
    res = simulate(_injection(160, -11.0, 1.15))
    f = res["inj_freq_Hz"]
    t = res["time_s"]
    assert np.all(f[t > 8.0] == 6.0)
    assert abs(drive_metrics(res)["R2_error_pct"]) < 1.0
    narrow = simulate(_injection(160, -11.0, 1.15, ("compensator.gate_band_pu=0.5",)))
    assert np.all(narrow["inj_freq_Hz"][t > 8.0] < 6.0)  # 2 or 4 Hz: a side band at 1 Hz
    assert abs(drive_metrics(narrow)["R2_error_pct"]) > 2.0


def test_the_harmonics_fit_the_decision_window():
    # the schedule's frequencies are whole multiples of the first: a window of whole periods
    # of it holds whole periods of each, and the old alternatives are dropped with a warning
    with pytest.warns(UserWarning, match="injection.frequency3_Hz"):
        sc = _injection(300, 6.0, 1.0, ("injection.frequency3_Hz=5.0",))
    from imdrive.config.perunit import resolve

    r = resolve(sc)
    assert (r.inj_f2, r.inj_f3) == (2 * r.inj_f1, 3 * r.inj_f1)
    assert r.n_comp * sc.simulation.Ts_s * r.inj_f3 == pytest.approx(3.0)


# ------------------------------------------------------------------------------------------
# field weakening: the MRAS keeps its bandwidth (mras.normalise, on with field weakening)


def _fw_ramp(extra=()):
    return Scenario.read(
        "sensorless",
        [
            "control.field_weakening=true",
            "control.speed_ref_rpm={initial=0,changes=[{at=0.5,to=900,over=1.0},"
            "{at=3,to=2300,over=1.8}]}",
            "load.torque_Nm={initial=0,changes=[{at=2.0,to=5}]}",
            "simulation.t_end_s=7",
            *extra,
        ],
    )


def test_fast_ramp_into_field_weakening_keeps_control():
    res = simulate(_fw_ramp())
    m = drive_metrics(res)
    assert not m["lost_control"]
    assert abs(res["speed_rpm"][-1] - 2300.0) < 2.0
    t = res["time_s"]
    lag = np.abs(res["speed_est_rpm"] - res["speed_rpm"])[t > 3.0]
    assert lag.max() < 150.0
    # without the normalisation the estimate falls hundreds of rpm behind
    off = simulate(_fw_ramp(("mras.normalise=false",)))
    lag_off = np.abs(off["speed_est_rpm"] - off["speed_rpm"])[t > 3.0]
    assert lag_off.max() > 2 * lag.max()


def test_mras_normalisation_changes_nothing_at_rated_flux():
    """Below base speed the flux is the design flux: the normalised MRAS gives the same run
    to within the flux ripple of the start-up (a few per mille of the gain)."""
    base = Scenario.read("sensorless", ["simulation.t_end_s=3"])
    a = simulate(base)
    b = simulate(base.with_overrides(["mras.normalise=true"]))
    t = a["time_s"]
    late = t > 2.5
    assert np.abs(a["speed_rpm"][late] - b["speed_rpm"][late]).max() < 0.5


def test_standstill_R1_identification_sees_the_dead_time_error():
    """The documented limit of one current level: on the uncommissioned realistic drive (2 us
    dead time compensated for 1.6 us) the residual dead-time voltage dominates R1 |i| at
    standstill (two levels: test_r1_two_levels.py)."""
    sc = Scenario.read(
        "sensorless-realistic-uncommissioned",
        ["mras.R1_standstill=true", "mras.R1_standstill_levels=1", "simulation.t_end_s=0.75"],
    )
    res = simulate(sc)
    assert res["R1_hat_ohm"][-1] / res["R1_ohm"][-1] > 1.5
    exact = Scenario.read(
        "sensorless-realistic-uncommissioned",
        [
            "mras.R1_standstill=true",
            "mras.R1_standstill_levels=1",
            "simulation.t_end_s=0.75",
            "inverter.dead_time_s=0",
            'control.dead_time_compensation="none"',
            # the switches' 1 V drops are a residual too: 0.46 R1 more at the magnetising
            # current (before, the window did not open here and the test read R1_hat(0))
            "inverter.device_drop_V=0",
        ],
    )
    res = simulate(exact)
    assert res["R1_id_status_code"][-1] == 1  # identified
    # 0.990 R1 (0.9898 without the sensors' noise, 0.9903 +- 0.0006 over ten noise seeds):
    # the saturating plant's build-up is not the one exponential the window fits
    assert 0.985 < res["R1_hat_ohm"][-1] / res["R1_ohm"][-1] < 1.0
