"""The online scaling of the inverter-error compensation (kernels/ifoc.py
``adapt_inverter_error``), on hand-made records.

Two checks that could fail independently of the drive:

* the six-step residual of a per-phase ``sgn(i_x)`` error, taken across the current vector,
  has the sixth-harmonic coefficient ``c6 = (8/pi)(1/10 + 1/14)`` the law divides by
  (computed here by quadrature of the exact six-step vector, not from the law's formula);
* fed the ripple that residual leaves in a current PI of bandwidth ``a_c`` (gain and lag of
  ``a_c/(s + a_c)`` at six times the stator frequency), plus a DC offset the law must ignore,
  the scale converges to the ratio of the true error to the assumed one, turning either way,
  and moves its share out of a standstill-identified R1.
"""

import math

import numpy as np
import pytest
from numba import njit

from imdrive.kernels.ifoc import (
    CONTROL_PARAMS,
    CONTROL_STATE,
    SIXTH_HARMONIC_HALF,
    adapt_inverter_error,
    standstill_compensation,
)
from imdrive.kernels.inverter import clarke
from imdrive.kernels.inverter_scale import stator_residual
from imdrive.kernels.model import MODEL_STATE, model_inductances
from imdrive.kernels.records import new_record

TS = 1e-4
A_C = 2 * math.pi * 200.0  # current-loop bandwidth, rad/s


def _six_step_across(theta, u=1.0):
    """The per-phase error ``u sgn(i_x)`` of a current at angle ``theta`` as a space vector,
    its component 90 degrees ahead of the current."""
    ia, ib, ic = (math.cos(theta - k * 2 * math.pi / 3) for k in range(3))
    e_a, e_b = clarke(u * np.sign(ia), u * np.sign(ib), u * np.sign(ic))
    return -math.sin(theta) * e_a + math.cos(theta) * e_b


def test_six_step_error_across_the_current_has_the_sixth_harmonic_the_law_assumes():
    th = (np.arange(36000) + 0.5) * 2 * math.pi / 36000
    perp = np.array([_six_step_across(t) for t in th])
    b6 = 2 * np.mean(perp * np.sin(6 * th))  # Fourier sine coefficient of the sixth harmonic
    assert b6 == pytest.approx(-2 * SIXTH_HARMONIC_HALF, rel=1e-4)
    assert 2 * SIXTH_HARMONIC_HALF == pytest.approx(96 / (70 * math.pi), rel=1e-12)
    # and nothing at the fundamental: the residual's along-current part is its DC
    assert abs(2 * np.mean(perp * np.sin(th))) < 1e-6


def _run_law(ratio, w_e, t_end=6.0, rate=2.0, u_c=1.2, ie_r1=False, c0=0.0, R1_id=False):
    p = new_record(
        CONTROL_PARAMS,
        ie_rate=rate,
        ie_wc=A_C,
        ie_wmin=2 * math.pi * 3.0,
        dtc_u=u_c,
        ie_r1=ie_r1,
    )
    s = np.zeros(1, dtype=CONTROL_STATE)
    s["ie_c0"] = c0
    m = new_record(
        MODEL_STATE, R1_hat=0.6, R2_hat=0.8, Ll1_hat=0.008, Ll2_hat=0.008, M_hat=0.2, R1_id=R1_id
    )
    k_seen = _law_loop(p, s, m, ratio, w_e, u_c, int(t_end / TS))
    return k_seen, s[0], m[0]


@njit
def _law_loop(p_arr, s_arr, m_arr, ratio, w_e, u_c, n):
    """The scale ``1 + ie_dk`` after each of ``n`` periods (compiled: from Python, each call
    unboxed three records, and 60,000 periods took 5-40 s)."""
    p, s, m = p_arr[0], s_arr[0], m_arr[0]
    i_d, i_q = 4.0, 3.0  # the current in the controller's frame (any angle to the d axis)
    gamma = math.atan2(i_q, i_d)
    w6 = 6 * abs(w_e)
    H = A_C / complex(A_C, w6)  # the closed current loop at the sixth harmonic (forward)
    th = 0.3
    k_seen = np.empty(n)
    for k in range(n):
        resid = ratio * u_c - (1.0 + s.ie_dk) * u_c  # what the compensation leaves
        th_i = th + gamma
        # the PI output across the current: the residual's sixth harmonic, through the loop
        # (its lag is in time, so an angle lead when turning backwards), plus a DC offset
        lag = math.atan2(H.imag, H.real) * (1 if w_e > 0 else -1)
        u_perp = -2 * SIXTH_HARMONIC_HALF * resid * abs(H) * math.sin(6 * th_i + lag) + 7.0
        # back to d, q components with that perpendicular part (and some along the current)
        u_d = (i_d * 2.0 - i_q * u_perp) / math.hypot(i_d, i_q)
        u_q = (i_q * 2.0 + i_d * u_perp) / math.hypot(i_d, i_q)
        adapt_inverter_error(p, s, m, u_d, u_q, i_d, i_q, th, w_e, TS)
        th += w_e * TS
        k_seen[k] = 1.0 + s.ie_dk
    return k_seen


@pytest.mark.parametrize("ratio", [0.8, 1.25])
@pytest.mark.parametrize("w_e", [2 * math.pi * 10.0, -2 * math.pi * 33.0])
def test_scale_converges_to_the_true_over_assumed_error(ratio, w_e):
    k, _, _ = _run_law(ratio, w_e)
    assert k[-1] == pytest.approx(ratio, rel=0.01)
    # about the first-order rate (2 /s): a third of the way after 0.25 s, not a jump
    quarter = k[int(0.25 / TS)]
    share = (quarter - 1.0) / (ratio - 1.0)
    assert 0.2 < share < 0.6


def test_below_its_frequency_the_scale_holds():
    k, _, _ = _run_law(1.25, 2 * math.pi * 2.0)
    assert np.all(k == 1.0)


def test_the_learned_share_leaves_a_standstill_R1():
    c0 = 0.2  # ohm of apparent resistance per unit of the compensation at standstill
    k, s, m = _run_law(1.25, 2 * math.pi * 10.0, ie_r1=True, c0=c0, R1_id=True)
    assert m["R1_hat"] == pytest.approx(0.6 - (k[-1] - 1.0) * c0, rel=1e-9)


def test_no_share_leaves_an_R1_the_standstill_run_did_not_identify():
    # the identification could not (R1_id false): R1_hat holds none of the residual
    k, s, m = _run_law(1.25, 2 * math.pi * 10.0, ie_r1=True, c0=0.2, R1_id=False)
    assert k[-1] == pytest.approx(1.25, rel=0.01)
    assert m["R1_hat"] == 0.6


@njit
def _six_step(theta, u):
    """The per-phase error ``u sgn(i_x)`` of a current at angle ``theta``, a complex vector."""
    ia = math.cos(theta)
    ib = math.cos(theta - 2 * math.pi / 3)
    ic = math.cos(theta - 4 * math.pi / 3)
    e_a, e_b = clarke(u * np.sign(ia), u * np.sign(ib), u * np.sign(ic))
    return complex(e_a, e_b)


def _run_stator_law(ratio, w_e, ripple, R1_hat, t_end=6.0, rate=2.0, u_c=1.2):
    """The law on the stator voltage equation's residual (``ie_veq``) of a machine whose
    current carries, besides the residual's own response, a sixth harmonic of any other origin
    (``ripple``, A, across the current: what a speed loop passes into ``iq*``)."""
    p = new_record(
        CONTROL_PARAMS, ie_rate=rate, ie_wc=A_C, ie_wmin=2 * math.pi * 3.0, dtc_u=u_c, ie_veq=True
    )
    s = np.zeros(1, dtype=CONTROL_STATE)
    m = new_record(MODEL_STATE, R1_hat=R1_hat, R2_hat=0.8, Ll1_hat=0.008, Ll2_hat=0.008, M_hat=0.2)
    return _stator_loop(p, s, m, ratio, w_e, ripple, u_c, int(t_end / TS))


@njit
def _current(th, gamma, ripple):
    th_i = th + gamma
    return (4.0 + 1j * ripple * math.sin(6 * th_i + 0.7)) * complex(math.cos(th_i), math.sin(th_i))


@njit
def _stator_loop(p_arr, s_arr, m_arr, ratio, w_e, ripple, u_c, n):
    """The scale ``1 + ie_dk`` after each of ``n`` periods (compiled, as :func:`_law_loop`)."""
    p, s, m = p_arr[0], s_arr[0], m_arr[0]
    _, _, _, sigma_L1 = model_inductances(m)
    R1, psi, gamma = 0.6, 0.5, 0.6  # the plant's R1, its back-emf's flux, the current's angle
    th = 0.3
    i_prev = _current(th - w_e * TS, gamma, ripple)
    s.w_e = w_e
    k_seen = np.empty(n)
    for k in range(n):
        i_k = _current(th, gamma, ripple)
        i_m = 0.5 * (i_k + i_prev)
        th_m = th - 0.5 * w_e * TS
        resid = (ratio - (1.0 + s.ie_dk)) * u_c  # what the compensation leaves, per phase
        emf = 1j * w_e * psi * complex(math.cos(th_m), math.sin(th_m))
        r = _six_step(math.atan2(i_m.imag, i_m.real), resid)
        v = sigma_L1 * (i_k - i_prev) / TS + R1 * i_m + emf + r  # less the compensation
        s.theta_e = th
        stator_residual(p, s, m, v, i_prev, i_k, TS)
        adapt_inverter_error(p, s, m, 0.0, 0.0, 0.0, 0.0, th, w_e, TS)
        i_prev = i_k
        th += w_e * TS
        k_seen[k] = 1.0 + s.ie_dk
    return k_seen


@pytest.mark.parametrize("ratio", [0.8, 1.25])
@pytest.mark.parametrize("w_e", [2 * math.pi * 10.0, -2 * math.pi * 90.0])
@pytest.mark.parametrize(("ripple", "R1_hat"), [(0.3, 0.6), (0.0, 0.78)])
def test_stator_voltage_form_converges_whatever_else_drives_the_current(ratio, w_e, ripple, R1_hat):
    # a sixth harmonic of the current from elsewhere (0.3 A, against the residual's 0.1-0.3 V),
    # or R1_hat 30 % off (it lies along the current and leaves the projection)
    k = _run_stator_law(ratio, w_e, ripple, R1_hat)
    assert k[-1] == pytest.approx(ratio, rel=0.01)
    quarter = k[int(0.25 / TS)]
    assert 0.2 < (quarter - 1.0) / (ratio - 1.0) < 0.6  # about the first-order rate, 2 /s


def test_standstill_apparent_resistance_of_the_compensation():
    s = np.zeros(1, dtype=CONTROL_STATE)[0]
    s["ie_dk"] = 0.25
    dv_a, dv_b = 1.5, -0.5
    standstill_compensation(s, dv_a, dv_b, 5.0, 1.0, 0.0)
    assert s["ie_c0"] == pytest.approx((dv_a * 5.0 + dv_b * 1.0) / (1.25 * 26.0), rel=1e-12)
    standstill_compensation(s, 9.0, 9.0, 5.0, 1.0, 1.0)  # the speed reference moved: held
    assert s["ie_c0"] == pytest.approx((dv_a * 5.0 + dv_b * 1.0) / (1.25 * 26.0), rel=1e-12)


@pytest.mark.parametrize(
    ("preset", "sets", "rate"),
    [
        ("sensorless-realistic-uncommissioned", [], 1.0),  # assumed dead time: adapts
        ("sensorless-realistic", [], 0.0),  # a commissioned table: held as measured
        ("sensorless-realistic", ["control.inverter_error_adaptation_per_s=0.5"], 0.5),
        ("sensorless-realistic-uncommissioned", ["control.inverter_error_adaptation_per_s=0"], 0.0),
    ],
)
def test_default_rate_follows_what_the_controller_knows_of_the_inverter(preset, sets, rate):
    from imdrive import Scenario
    from imdrive.run.build import build_arrays

    p = build_arrays(Scenario.read(preset, sets)).params.control[0]
    assert p["ie_rate"] == rate
