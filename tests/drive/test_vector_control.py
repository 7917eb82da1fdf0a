"""Indirect field-oriented control and Schauder's MRAS: the sensorless vector drive.

Every test runs the drive to a steady state and compares with theory: the field-orientation
conditions, the equivalent-circuit steady state of the sensorless drive (imdrive.analysis), and
the integrator's response to a DC current offset.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from imdrive import analysis
from imdrive.cli import main
from imdrive.config.machine import machine_preset
from imdrive.config.perunit import speed_bandwidth_Hz
from imdrive.config.scenario import Scenario
from imdrive.errors import SimulationDiverged
from imdrive.run.simulate import simulate

MACHINE = machine_preset("paper-table-iv")
RATED_LOAD = 12.0  # N m, about the rated torque of the 3 hp machine


def drive(speed_rpm, load_Nm, *, feedback="mras", R2_ratio=1.0, t_end=4.0, **sections):
    """A vector-controlled drive: magnetise, ramp to speed, load at 1.5 s, run to t_end."""
    data = {
        "name": "test",
        "drive": {"mode": "vector"},
        "control": {
            "speed_feedback": feedback,
            "speed_ref_rpm": {
                "initial": 0.0,
                "changes": [{"at": 0.3, "to": float(speed_rpm), "over": 0.7}],
            },
        },
        "load": {"torque_Nm": {"initial": 0.0, "changes": [{"at": 1.5, "to": float(load_Nm)}]}},
        "estimator": {"R2_ohm": MACHINE.R2_ohm * R2_ratio},
        "simulation": {"t_end_s": t_end, "Ts_s": 1e-4, "log_every": 1},
    }
    for key, val in sections.items():
        data.setdefault(key, {}).update(val)
    return simulate(Scenario.from_dict(data))


def tail(res, seconds=0.5):
    return res.window(res.time_s[-1] - seconds)


def wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


# ---------------------------------------------------------------------------------------------
# sensored control with exact parameters


@pytest.fixture(scope="module")
def sensored():
    return drive(1000.0, RATED_LOAD, feedback="measured")


def test_sensored_flux_magnitude_follows_reference(sensored):
    w = tail(sensored)
    flux_ref = MACHINE.rated_flux_Wb
    assert not sensored.diverged
    assert np.max(np.abs(w["flux_Wb"] / flux_ref - 1.0)) < 0.005


def test_sensored_orientation_error_below_1_mrad(sensored):
    # angle between the plant's rotor flux and the controller's d axis at each sample
    w = tail(sensored)
    flux_angle = np.arctan2(w["psi_r_beta_Wb"], w["psi_r_alpha_Wb"])
    err = wrap(flux_angle - w["theta_e_rad"])
    assert np.max(np.abs(err)) < 1e-3
    # and the torque-producing current really produces the load torque
    assert abs(np.mean(w["torque_Nm"]) - RATED_LOAD) < 0.01 * RATED_LOAD


def test_sensored_zero_steady_state_speed_error(sensored):
    w = tail(sensored)
    assert abs(np.mean(w["speed_rpm"] - w["speed_ref_rpm"])) < 1e-3
    assert np.ptp(w["speed_rpm"]) < 1e-2


# ---------------------------------------------------------------------------------------------
# sensorless with exact parameters


@pytest.mark.parametrize("speed_rpm", [1000.0, 150.0])
def test_sensorless_speed_estimate_error_below_0p1_rpm(speed_rpm):
    res = drive(speed_rpm, RATED_LOAD, feedback="mras")
    w = tail(res)
    assert not res.diverged
    assert abs(np.mean(w["torque_Nm"]) - RATED_LOAD) < 0.02 * RATED_LOAD
    est_err = np.mean(w["speed_est_rpm"] - w["speed_rpm"])
    assert abs(est_err) < 0.1
    assert abs(np.mean(w["speed_rpm"] - speed_rpm)) < 0.1


# ---------------------------------------------------------------------------------------------
# the detuning law of the sensorless drive


@pytest.mark.slow
@pytest.mark.parametrize("R2_ratio", [0.8, 1.2])
@pytest.mark.parametrize("speed_rpm", [1000.0, 300.0])
@pytest.mark.parametrize("load_Nm", [6.0, RATED_LOAD])
def test_detuning_law(R2_ratio, speed_rpm, load_Nm):
    """Actual speed = reference + slip_mech * (R2_hat/R2 - 1), within 2 % of that deviation."""
    op = analysis.foc_operating_point(MACHINE, speed_rpm, load_Nm, R2_ratio=1.0)
    predicted = op.slip_mech_rpm * (R2_ratio - 1.0)
    res = drive(speed_rpm, load_Nm, feedback="mras", R2_ratio=R2_ratio, t_end=5.0)
    w = tail(res)
    deviation = np.mean(w["speed_rpm"] - w["speed_ref_rpm"])
    assert np.sign(deviation) == np.sign(R2_ratio - 1.0)
    assert abs(deviation - predicted) <= 0.02 * abs(predicted)
    # the estimate still follows the reference: the error is invisible to the drive
    assert abs(np.mean(w["speed_est_rpm"] - w["speed_ref_rpm"])) < 0.1


# ---------------------------------------------------------------------------------------------
# Schauder's integrator replacement against a DC current-sensor offset


def _dc_component(res, t0, t1, period):
    """Mean of the reference-model flux over whole electrical periods ending at t1."""
    n = int(round((t1 - t0) / period))
    w = res.window(t1 - n * period, t1)
    # drop the closing sample so the window spans exactly n periods
    return complex(np.mean(w["lam_v_alpha_Wb"][:-1]), np.mean(w["lam_v_beta_Wb"][:-1]))


@pytest.mark.parametrize("wc", [0.0, 5.0])
def test_integrator_choice_under_current_offset(wc):
    offset = 0.05  # A on the measured i_alpha
    res = drive(
        1000.0,
        0.0,
        feedback="measured",
        t_end=4.0,
        mras={"wc_rad_s": wc},
        sensor={"i_offset_alpha_A": offset},
    )
    assert not res.diverged
    period = 1.0 / (1000.0 / 60.0 * MACHINE.pole_pairs)  # no load: no slip
    drift_rate = -(MACHINE.L2_H / MACHINE.M_H) * MACHINE.R1_ohm * offset  # Wb/s, alpha axis
    d1 = _dc_component(res, 2.0, 2.5, period)
    d2 = _dc_component(res, 3.5, 4.0, period)
    if wc == 0.0:
        # pure integrator: the DC component grows linearly without bound
        slope = (d2.real - d1.real) / 1.5
        assert slope == pytest.approx(drift_rate, rel=0.02)
        assert abs(d2) > abs(d1) + 0.9 * abs(drift_rate) * 1.5
    else:
        # low-pass replacement: bounded, settled at rate/wc
        assert d2.real == pytest.approx(drift_rate / wc, rel=0.02)
        assert abs(d2 - d1) < 0.02 * abs(drift_rate / wc)


# ---------------------------------------------------------------------------------------------
# divergence is reported, not hidden


# A current PI with negative gain on a DC link so high that the voltage limit never acts: the
# currents grow exponentially until they pass the divergence bound (100 x rated by default):
# a current gain far above the discrete stability limit 2 sigma L1 / Ts ~ 79 V/A.
# (With the default 311 V link the inverter's limit keeps an unstable drive bounded.)
UNSTABLE = ["control.current_kp=150.0", "inverter.Vdc_V=1e5", "simulation.t_end_s=1.0"]


def _unstable():
    return [a for ov in UNSTABLE for a in ("--set", ov)]


def test_divergence_is_reported_with_time_and_signal():
    res = simulate(Scenario.read("sensorless", UNSTABLE))
    assert res.diverged
    assert 0 < res.end_time_s < 1.0
    assert "diverged at t =" in res.divergence_message
    assert "|i_s|" in res.divergence_message
    assert res.summary()["diverged_signal"] == "i_s_A"
    assert len(res.time_s) >= 1 and res.time_s[-1] <= res.end_time_s
    assert np.all(np.isfinite(res["i_alpha_A"]))
    with pytest.raises(SimulationDiverged, match="diverged at t =") as exc:
        res.raise_if_diverged()
    assert exc.value.result is res and exc.value.time_s == res.end_time_s


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_cli_divergence_exit_code_and_partial_results(tmp_path, capsys):
    out = tmp_path / "run"
    rc = main(["run", "sensorless", "--out", str(out), "-q", *_unstable()])
    assert rc == 1
    err = capsys.readouterr().err
    assert "diverged at t =" in err and "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["diverged"] is True
    assert 0 < summary["diverged_at_s"] < 1.0
    assert summary["diverged_signal"] in ("state", "i_s_A", "speed_rpm")
    assert (out / "timeseries.csv").exists()


def test_controller_gain_formulas():
    """The documented bandwidth formulas give the gains written into summary.json."""
    sc = Scenario.read("sensorless")
    res = simulate(sc.with_(simulation=sc.simulation.__class__(t_end_s=0.01)))
    d = res.derived
    m = MACHINE
    a_c = 2 * math.pi * sc.control.current_bandwidth_Hz
    sigma_L1 = m.L1_H - m.M_H**2 / m.L2_H
    assert d["current_kp"] == pytest.approx(sigma_L1 * a_c)
    assert d["current_ki"] == pytest.approx((m.R1_ohm + (m.M_H / m.L2_H) ** 2 * m.R2_ohm) * a_c)
    k_t = 1.5 * m.pole_pairs * m.M_H / m.L2_H * m.rated_flux_Wb
    a_s = 2 * math.pi * speed_bandwidth_Hz(sc)  # derived from the machine (5 Hz here)
    assert d["speed_kp"] == pytest.approx(m.J_kgm2 * a_s / k_t)
    assert d["mras_K2"] / d["mras_K1"] == pytest.approx(m.R2_ohm / m.L2_H)
