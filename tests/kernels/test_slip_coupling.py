"""``slip_coupling``: the d-axis flux error the slip couples in from the q-axis error."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from imdrive.kernels.compensator import COMPENSATOR_STATE
from imdrive.kernels.detection import MAX_HP_CORRECTION, slip_coupling


@njit
def _couple(e, w_e, wc, w_s, T2, Ts):
    """``slip_coupling`` of a fresh state, one call per sample of the error ``e``; its outputs.

    The loop is compiled: called from Python, each call unboxes a record (about 0.1 ms), and
    the sinusoid's 350,000 periods took 50 s."""
    state = np.zeros(1, dtype=COMPENSATOR_STATE)
    s = state[0]
    out = np.empty(e.shape[0])
    for k in range(e.shape[0]):
        out[k] = slip_coupling(s, e[k], w_e, wc, w_s, T2, Ts)
    return out


@pytest.mark.parametrize("w_s, T2, f", [(30.0, 0.1, 2.0), (-12.0, 0.25, 4.0), (5.0, 0.05, 1.0)])
def test_sinusoidal_q_error_gives_the_first_order_response(w_s, T2, f):
    """A q error ``Q sin(w t)`` gives, once settled, ``Im(G(jw) Q e^{jwt})`` with
    ``G = w_s T2 / (1 + j w T2)`` (the rotor's d-flux equation)."""
    Ts = 1e-5
    w = 2 * math.pi * f
    Q = 1e-3
    G = w_s * T2 / (1 + 1j * w * T2)
    n = int(round(12 * T2 / Ts)) + int(round(2 / f / Ts))
    t = np.arange(n) * Ts
    c = _couple(1j * Q * np.sin(w * t), 300.0, 0.0, w_s, T2, Ts)
    settled = t > 10 * T2
    want = (G * Q * np.exp(1j * w * (t[settled] + Ts))).imag
    err = np.max(np.abs(c[settled] - want))
    assert err < 2e-3 * abs(G) * Q + 1e-12


def test_constant_q_error_settles_at_the_dc_gain():
    c = _couple(np.full(20000, complex(0.0, 2e-3)), 300.0, 0.0, 40.0, 0.08, 1e-4)[-1]
    assert c == pytest.approx(40.0 * 0.08 * 2e-3, rel=1e-6)


@pytest.mark.parametrize("w_e", [45.0, -45.0, 2.0, -2.0])
def test_filter_leakage_of_the_d_error_is_taken_out(w_e):
    """Through the MRAS's ``s/(s + wc)`` a d error leaks ``wc/w_e`` of itself into q: a pure d
    error couples nothing; the ratio is bounded near w_e = 0."""
    wc = 15.0
    c = _couple(np.full(50000, complex(1e-3, 0.0)), w_e, wc, 10.0, 0.1, 1e-4)[-1]
    ratio = min(wc / abs(w_e), MAX_HP_CORRECTION)
    assert c == pytest.approx(-math.copysign(ratio, w_e) * 1e-3 * 10.0 * 0.1, rel=1e-6)
    # the leaked share itself cancels
    e = complex(1e-3, math.copysign(ratio, w_e) * 1e-3)
    c2 = _couple(np.full(50000, e), w_e, wc, 10.0, 0.1, 1e-4)[-1]
    assert abs(c2) < 1e-15
