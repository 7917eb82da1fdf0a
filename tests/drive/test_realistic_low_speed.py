"""The adaptive observer and the EKF at low speed on the realistic drive, on three machines
(docs/estimators.md, *Low speed on the realistic drive*): ``sensorless-realistic`` with only
the machine and the estimator changed, at 5 and 10 % of the rated speed, with the rated
motoring torque, without load and regenerating half of it (1.5-8.4 Hz of stator frequency),
R2_hat = R2. Measured: every run within 0.37 rpm of its reference. Before 2026-11-29 (the
commissioned inverter-error table replaced the bridge's loss shape, and the observer's gain
was its regeneration gain throughout) the observer lost control in 7 of these 18 runs on
Table IV and Krause 50 hp and ended up to 62 rpm off in the others, the EKF up to 7.6 rpm.
"""

from __future__ import annotations

import math

import pytest

from imdrive.studies import machines

MACHINES = ("paper-table-iv", "aalto-2.2kw", "krause-50hp")


@pytest.mark.slow
@pytest.mark.parametrize("estimator", ["afo", "ekf"])
def test_the_observers_hold_low_speed_on_the_realistic_drive(monkeypatch, estimator):
    drive = f"realistic-{estimator}"
    alias = ("sensorless-realistic", (f'control.speed_feedback="{estimator}"',))
    monkeypatch.setitem(machines.DRIVE_ALIASES, drive, alias)
    t = machines.run(
        MACHINES, drives=(drive,), speeds=(0.05, 0.1), loads=(1.0, 0.0, -0.5), ratios=(1.0,)
    )
    assert len(t) == 18
    assert not t["lost_control"].any()
    assert (t["f_s_R2_Hz"].abs() > 1.0).all()  # away from zero stator frequency
    worst = t["speed_error_rpm"].abs().max()
    assert worst < 0.5, t[["machine", "speed_pu", "load_pu", "speed_error_rpm"]]


def _afo_70rpm_regenerating(preset: str, *extra: str):
    import warnings

    import imdrive as im
    from imdrive.errors import ConfigWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        sc = im.Scenario.read(
            preset,
            [
                'control.speed_feedback="afo"',
                "control.speed_ref_rpm={initial=0, changes=[{at=0.5, to=70, over=1.0}]}",
                "load.torque_Nm={initial=0, changes=[{at=2.0, to=-12}]}",
                "simulation.t_end_s=6.0",
                *extra,
            ],
        )
    res = im.simulate(sc)
    return not math.isnan(res.lost_control_at_s), res.signals["speed_rpm"][-1] - 70.0


@pytest.mark.slow
def test_calibrating_the_current_sensors_keeps_the_observer_near_zero_frequency():
    # docs/estimators.md: 70 rpm regenerating the rated torque on Table IV puts the stator
    # frequency at -0.3 Hz; the ideal drive holds it. The realistic drive, its sensors'
    # gains 0.5 % apart, holds it with its commissioned calibration of their relative gain
    # (controller_model.current_gain_b_per_a), and loses control without it; without its
    # dead time and device drop (nothing compensated) it holds it uncalibrated too
    lost, err = _afo_70rpm_regenerating("sensorless")
    assert not lost and abs(err) < 1.0
    lost, err = _afo_70rpm_regenerating("sensorless-realistic")  # measured -0.48 rpm at 6 s
    assert not lost and abs(err) < 3.0, err
    # calibrated to within 0.05 % either way (the DC test finds it within 0.02 %): -0.31,
    # -0.67 rpm
    for ratio in (0.9975 / 1.0025 * 1.0005, 0.9975 / 1.0025 * 0.9995):
        lost, err = _afo_70rpm_regenerating(
            "sensorless-realistic", f"controller_model.current_gain_b_per_a={ratio}"
        )
        assert not lost and abs(err) < 3.0, err
    lost, _ = _afo_70rpm_regenerating(
        "sensorless-realistic", "controller_model.current_gain_b_per_a=1"
    )
    assert lost
    lost, err = _afo_70rpm_regenerating(
        "sensorless-realistic",
        "controller_model.current_gain_b_per_a=1",
        "inverter.dead_time_s=0",
        "inverter.device_drop_V=0",
    )
    assert not lost and abs(err) < 5.0
