"""The field-oriented controller's kernels alone, on hand-made records (kernels/ifoc.py).

Each check is a formula of the module docstring evaluated independently: the slip
``(R2_hat/L2_hat) iq*/id*`` of indirect field orientation, the decoupling feed-forward, the
current limit with the d axis first, the PI's back-calculation anti-windup, field weakening by
voltage feedback, and the dead-time feed-forward as the exact opposite of the inverter's
averaged dead-time error.
"""

import math

import numpy as np
import pytest

from imdrive.kernels.ifoc import (
    CONTROL_PARAMS,
    CONTROL_STATE,
    dead_time_feedforward,
    field_weakening,
    foc_step,
)
from imdrive.kernels.inverter import INVERTER_PARAMS, pole_error
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.records import new_record

TS = 1e-4
N_P = 2.0
M, LL1, LL2 = 0.2, 0.008, 0.008
L1, L2 = LL1 + M, LL2 + M
SIGMA_L1 = L1 - M * M / L2
PSI = 0.8


def _model(R2_hat=0.8):
    return new_record(MODEL_STATE, R1_hat=1.0, R2_hat=R2_hat, Ll1_hat=LL1, Ll2_hat=LL2, M_hat=M)[0]


def _params(**kw):
    values = {"n_p": N_P, "i_max": 20.0, "v_max": 300.0, "angle_advance": 0.5, **kw}
    return new_record(CONTROL_PARAMS, **values)[0]


def _magnetised(iq_cmd):
    """A controller in steady state: the flux model at ``M id*``, the speed PI's integral
    holding the torque command ``iq_cmd`` (zero speed error)."""
    s = np.zeros(1, dtype=CONTROL_STATE)[0]
    s["psi_hat"] = PSI
    s["int_w"] = iq_cmd
    return s


@pytest.mark.parametrize("R2_hat", [0.5, 0.8, 1.2])
@pytest.mark.parametrize("iq", [3.0, -6.0])
def test_slip_is_R2_hat_over_L2_times_iq_over_id(R2_hat, iq):
    p, m, s = _params(kp_w=0.1), _model(R2_hat), _magnetised(iq)
    w_m = 100.0
    foc_step(p, m, s, 0.0, 0.0, w_m, w_m, PSI, 0.0, TS, 0j, 0.0)
    id_ref = PSI / M
    assert s["i_ref_dq"] == pytest.approx(complex(id_ref, iq), rel=1e-12)
    slip = (R2_hat / L2) * iq / id_ref
    assert s["w_e"] == pytest.approx(N_P * w_m + slip, rel=1e-12)
    assert s["theta_e"] == pytest.approx(s["w_e"] * TS, rel=1e-12)
    assert s["psi_hat"] == pytest.approx(PSI, rel=1e-12)  # the flux model's fixed point


def test_decoupling_feed_forward_is_the_steady_state_voltage_less_the_resistive_drop():
    """With the PIs' gains and states at zero the voltage is the feed-forward alone:
    ``v_d = -w_e sigma L1 iq*``, ``v_q = w_e (sigma L1 id* + (M/L2) psi_hat)``, rotated by the
    field angle half a period ahead."""
    iq, w_m = 5.0, 80.0
    p, m, s = _params(decouple=True, angle_advance=0.5), _model(), _magnetised(iq)
    va, vb = foc_step(p, m, s, 0.0, 0.0, w_m, w_m, PSI, 0.0, TS, 0j, 0.0)
    w_e = s["w_e"]
    id_ref = PSI / M
    v_dq = complex(-w_e * SIGMA_L1 * iq, w_e * (SIGMA_L1 * id_ref + M / L2 * PSI))
    v_ab = v_dq * np.exp(1j * 0.5 * w_e * TS)
    assert complex(va, vb) == pytest.approx(v_ab, rel=1e-12)
    s2 = _magnetised(iq)
    assert foc_step(_params(), m, s2, 0.0, 0.0, w_m, w_m, PSI, 0.0, TS, 0j, 0.0) == (0.0, 0.0)


def test_measured_current_is_rotated_into_the_field_frame():
    p, m, s = _params(), _model(), _magnetised(0.0)
    s["theta_e"] = 0.7
    i_dq = complex(3.0, -2.0)
    i_ab = i_dq * np.exp(1j * 0.7)
    foc_step(p, m, s, i_ab.real, i_ab.imag, 0.0, 0.0, PSI, 0.0, TS, 0j, 0.0)
    assert s["i_s_dq"] == pytest.approx(i_dq, rel=1e-12)


@pytest.mark.parametrize("w_e, observed", [(100.0, True), (20.0, False)])
def test_an_observed_flux_sets_the_frame_above_the_threshold(w_e, observed):
    """Direct field orientation: with the estimator's flux given and the stator frequency at
    least ``dfo_wmin``, the current is rotated by the flux's angle (not the integrated one),
    and the next sample's angle runs on from it; below, the integrated angle."""
    p, m, s = _params(dfo_wmin=50.0), _model(), _magnetised(0.0)
    s["theta_e"] = 0.7
    s["w_e"] = w_e
    psi_obs = PSI * np.exp(1j * 1.1)
    th = 1.1 if observed else 0.7
    i_dq = complex(3.0, -2.0)
    i_ab = i_dq * np.exp(1j * th)
    foc_step(p, m, s, i_ab.real, i_ab.imag, 0.0, 0.0, PSI, 0.0, TS, psi_obs, 0.0)
    assert s["i_s_dq"] == pytest.approx(i_dq, rel=1e-12)
    assert s["theta_e"] == pytest.approx(th + s["w_e"] * TS, rel=1e-12)
    # an estimate below half the reference flux (magnetising) leaves the integrated angle
    p, m, s = _params(dfo_wmin=50.0), _model(), _magnetised(0.0)
    s["theta_e"], s["w_e"] = 0.7, w_e
    i_ab = i_dq * np.exp(1j * 0.7)
    foc_step(p, m, s, i_ab.real, i_ab.imag, 0.0, 0.0, PSI, 0.0, TS, 0.4 * psi_obs, 0.0)
    assert s["i_s_dq"] == pytest.approx(i_dq, rel=1e-12)


def test_current_limit_gives_the_d_axis_priority():
    i_max = 10.0
    p, m = _params(i_max=i_max, kp_w=50.0), _model()
    s = _magnetised(0.0)
    foc_step(p, m, s, 0.0, 0.0, 0.0, 300.0, PSI, 0.0, TS, 0j, 0.0)  # a large speed error
    id_ref = PSI / M
    assert s["i_ref_dq"].real == id_ref
    assert s["i_ref_dq"].imag == pytest.approx(math.sqrt(i_max**2 - id_ref**2), rel=1e-12)
    assert abs(s["i_ref_dq"]) == pytest.approx(i_max, rel=1e-12)
    s = _magnetised(0.0)
    foc_step(p, m, s, 0.0, 0.0, 300.0, 0.0, PSI, 0.0, TS, 0j, 0.0)
    assert s["i_ref_dq"].imag == pytest.approx(-math.sqrt(i_max**2 - id_ref**2), rel=1e-12)
    s = _magnetised(0.0)
    foc_step(p, m, s, 0.0, 0.0, 0.0, 300.0, 4.0, 0.0, TS, 0j, 0.0)  # id* alone beyond the limit
    assert s["i_ref_dq"] == complex(i_max, 0.0)


def test_speed_pi_anti_windup_restarts_from_the_limit():
    """After saturation the integral is back-calculated: the next unsaturated output is the
    limit plus one integral step, not the wound-up sum."""
    kp, ki, i_max = 2.0, 40.0, 10.0
    p, m = _params(kp_w=kp, ki_w=ki, i_max=i_max), _model()
    s = _magnetised(0.0)
    err = 30.0
    foc_step(p, m, s, 0.0, 0.0, 0.0, err, PSI, 0.0, TS, 0j, 0.0)
    iq_lim = s["i_ref_dq"].imag
    assert iq_lim == pytest.approx(math.sqrt(i_max**2 - (PSI / M) ** 2))
    assert s["int_w"] == pytest.approx(iq_lim - kp * err + ki * TS * err, rel=1e-12)


@pytest.mark.slow  # 1.5 s or more on 2 cores (5.6 s measured 2026-11-29)
def test_field_weakening_integrates_the_voltage_headroom():
    p = _params(fw=True, fw_v=0.9, fw_rate=20.0, fw_min=0.3)
    s = np.zeros(1, dtype=CONTROL_STATE)[0]
    assert field_weakening(p, s, 0.5, TS) == 1.0  # below base speed: rated flux
    assert s["fw_cut"] == 0.0
    k = field_weakening(p, s, 0.95, TS)  # above: the factor falls at fw_rate (v - fw_v)
    assert k == pytest.approx(1.0 - TS * 20.0 * 0.05, rel=1e-12)
    assert s["fw_cut"] == pytest.approx(1.0 - k, rel=1e-12)
    # from the Python side each call costs ~1 ms (the record's type is read anew): run just
    # past the time the integrator needs, 0.7 / (20 x 0.1) = 0.35 s down, 0.7 / 18 s back up
    for _ in range(int(1.1 * 0.7 / (20.0 * 0.1) / TS)):
        k = field_weakening(p, s, 1.0, TS)
    assert k == 0.3  # clamped at fw_min
    for _ in range(int(1.1 * 0.7 / (20.0 * 0.9) / TS)):
        k = field_weakening(p, s, 0.0, TS)
    assert k == 1.0  # and back to rated flux when the voltage has room


@pytest.mark.parametrize("i", [(10.0, 0.0), (-2.0, 5.0), (0.05, 0.02)])
def test_dead_time_feedforward_cancels_the_averaged_dead_time_error(i):
    t_d, f_sw, vdc, band = 2e-6, 1e4, 540.0, 0.2
    inv = new_record(INVERTER_PARAMS, Vdc=vdc, t_d=t_d, f_sw=f_sw, i_band=band)[0]
    ctl = _params(dtc_u=t_d * f_sw * vdc, dtc_band=band)
    ff = dead_time_feedforward(ctl, *i)
    err = pole_error(inv, i[0], i[1], 1.0 / f_sw)
    assert ff == pytest.approx(tuple(-e for e in err), abs=1e-12)
    assert dead_time_feedforward(_params(), *i) == pytest.approx((0.0, 0.0), abs=0.0)


def test_the_magnetising_curve_is_read_at_the_flux_magnitude_given():
    """``psi_mag`` (an encoder drive's R2-independent flux, the MRAS's): the saturation-aware
    model reads its curve there instead of at the flux model's (0: the flux model's)."""
    from imdrive.config.scenario import Scenario
    from imdrive.kernels.model import update_magnetising
    from imdrive.run.build import build_arrays

    m0 = build_arrays(Scenario.read("sensorless-realistic")).state0.model[0]
    assert m0["sat_n"] > 0
    psi = 0.7  # Wb: Table IV's rated flux is 0.716
    out = {}
    for psi_mag in (0.0, 1.15 * psi):
        m = m0.copy()
        s = _magnetised(3.0)
        s["psi_hat"] = psi
        foc_step(_params(kp_w=0.1), m, s, 0.0, 0.0, 100.0, 100.0, psi, 0.0, TS, 0j, psi_mag)
        ref = m0.copy()  # the update from the same start, at the flux foc_step should use
        update_magnetising(ref, psi_mag if psi_mag > 0.0 else s["psi_hat"], s["i_ref_dq"])
        assert m["M_hat"] == ref["M_hat"] and m["L_inc_hat"] == ref["L_inc_hat"]
        out[psi_mag] = m["M_hat"]
    assert out[1.15 * psi] < out[0.0]  # deeper in saturation: a smaller secant
