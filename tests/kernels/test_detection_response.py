"""The detection's in-phase response to an R2 error (imdrive.kernels.detection_response): the
phasor formulas against a time-domain integration of the error equations (scipy solve_ivp)
and a synchronous detection of the result, and the limits the law's sensitivity is."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from imdrive.kernels.detection_response import in_phase_response, responses
from imdrive.kernels.sensitivity import in_phase_sensitivity

#: Table IV regenerating the rated torque: T2 = L2/R2, the rated slip (60 Hz x 0.0439).
T2_IV = (0.0693 + 0.002) / 0.816
W_SL_IV = -2.0 * math.pi * 60.0 * 0.043926


def _detected(w_i, T2, w_sl, coupled, periods=40):
    """The in-phase part of ``e_d`` per unit of ``M a r``, by integrating the error equations
    of the module docstring over whole injection periods after the transient (M a = 1, r = 1):
    the rotor flux's d axis answers ``sin(w_i t)`` through ``1/(1 + s T2)``."""

    def rhs(t, y):
        psi, e_d, e_q = y
        i_d = math.sin(w_i * t)
        dpsi = (i_d - psi) / T2
        F_q = -w_sl * psi if coupled else 0.0
        return [
            dpsi,
            -e_d / T2 + w_sl * e_q + dpsi,
            -e_q / T2 - w_sl * e_d + F_q,
        ]

    T = 2.0 * math.pi / w_i
    t_end = periods * T
    t = np.linspace(t_end - 10 * T, t_end, 20001)
    sol = solve_ivp(rhs, (0.0, t_end), [0.0, 0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-12)
    e_d = sol.y[1]
    return 2.0 * np.trapezoid(e_d * np.sin(w_i * t), t) / (t[-1] - t[0])


@pytest.mark.parametrize("f_i", [0.5, 1.1, 2.0, 4.0])
def test_the_decoupled_response_is_the_laws_sensitivity(f_i):
    w_i = 2.0 * math.pi * f_i
    S = in_phase_sensitivity(w_i, T2_IV)
    assert in_phase_response(w_i, T2_IV, W_SL_IV, 0.0, 0.0, False) == pytest.approx(S, rel=1e-12)
    # without forcing on q the slip coupling leaves e_d's in-phase part alone only at w_sl = 0
    assert in_phase_response(w_i, T2_IV, 0.0, 0.0, 0.0, True) == pytest.approx(S, rel=1e-12)
    assert _detected(w_i, T2_IV, 0.0, False) == pytest.approx(S, abs=2e-4)


@pytest.mark.parametrize(
    ("f_i", "T2", "w_sl"),
    [(1.1, T2_IV, W_SL_IV), (3.3, T2_IV, W_SL_IV), (0.9, 0.156, -19.9), (0.19, 0.783, -5.65)],
)
def test_the_slip_coupled_response_against_a_time_domain_integration(f_i, T2, w_sl):
    """The phasor formula of the slip-coupled response (h1) is the integrated equations'
    synchronous detection, on Table IV, Krause 50 hp and Krause 500 hp's rated slips."""
    w_i = 2.0 * math.pi * f_i
    h0, h1 = responses(w_i, T2, w_sl, 0.0, 0.0)
    assert in_phase_response(w_i, T2, w_sl, 0.0, 0.0, True) == min(h0, h1)
    measured = _detected(w_i, T2, w_sl, True)
    assert measured == pytest.approx(h1, abs=2e-3 + 0.01 * abs(h1))


def test_the_slip_coupling_turns_the_sign_at_the_first_frequency_regenerating():
    """Table IV regenerating the rated torque: at 1.1 Hz the response is negative (the law
    would walk R2_hat away), at twice the frequency positive again."""
    lo = in_phase_response(2.0 * math.pi * 1.1, T2_IV, W_SL_IV, 0.0, 0.0, True)
    hi = in_phase_response(2.0 * math.pi * 2.2, T2_IV, W_SL_IV, 0.0, 0.0, True)
    assert lo < -0.2
    assert hi > 0.3


def test_the_comparison_filter_fades_out_far_from_its_corner():
    w_i = 2.0 * math.pi * 2.0
    S = in_phase_sensitivity(w_i, T2_IV)
    far = in_phase_response(w_i, T2_IV, W_SL_IV, 2.0 * math.pi * 60.0, 15.0, False)
    near = in_phase_response(w_i, T2_IV, W_SL_IV, 2.0 * math.pi * 0.5, 15.0, False)
    assert far == pytest.approx(S, rel=0.01)
    assert near < 0.5 * S
