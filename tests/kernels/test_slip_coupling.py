"""``slip_coupling``: the d-axis flux error the slip couples in from the q-axis error."""

from __future__ import annotations

import cmath
import math

import numpy as np
import pytest

from imdrive.kernels.compensator import COMPENSATOR_STATE
from imdrive.kernels.detection import MAX_HP_CORRECTION, slip_coupling


def _state():
    return np.zeros(1, dtype=COMPENSATOR_STATE)[0]


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@pytest.mark.parametrize("w_s, T2, f", [(30.0, 0.1, 2.0), (-12.0, 0.25, 4.0), (5.0, 0.05, 1.0)])
def test_sinusoidal_q_error_gives_the_first_order_response(w_s, T2, f):
    """A q error ``Q sin(w t)`` gives, once settled, ``Im(G(jw) Q e^{jwt})`` with
    ``G = w_s T2 / (1 + j w T2)`` (the rotor's d-flux equation)."""
    s = _state()
    Ts = 1e-5
    w = 2 * math.pi * f
    Q = 1e-3
    G = w_s * T2 / (1 + 1j * w * T2)
    n = int(round(12 * T2 / Ts)) + int(round(2 / f / Ts))
    err = 0.0
    for k in range(n):
        t = k * Ts
        c = slip_coupling(s, complex(0.0, Q * math.sin(w * t)), 300.0, 0.0, w_s, T2, Ts)
        if t > 10 * T2:
            want = (G * Q * cmath.exp(1j * w * (t + Ts))).imag
            err = max(err, abs(c - want))
    assert err < 2e-3 * abs(G) * Q + 1e-12


def test_constant_q_error_settles_at_the_dc_gain():
    s = _state()
    for _ in range(20000):
        c = slip_coupling(s, complex(0.0, 2e-3), 300.0, 0.0, 40.0, 0.08, 1e-4)
    assert c == pytest.approx(40.0 * 0.08 * 2e-3, rel=1e-6)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@pytest.mark.parametrize("w_e", [45.0, -45.0, 2.0, -2.0])
def test_filter_leakage_of_the_d_error_is_taken_out(w_e):
    """Through the MRAS's ``s/(s + wc)`` a d error leaks ``wc/w_e`` of itself into q: a pure d
    error couples nothing; the ratio is bounded near w_e = 0."""
    wc = 15.0
    s = _state()
    for _ in range(50000):
        c = slip_coupling(s, complex(1e-3, 0.0), w_e, wc, 10.0, 0.1, 1e-4)
    ratio = min(wc / abs(w_e), MAX_HP_CORRECTION)
    assert c == pytest.approx(-math.copysign(ratio, w_e) * 1e-3 * 10.0 * 0.1, rel=1e-6)
    # the leaked share itself cancels
    s2 = _state()
    for _ in range(50000):
        e = complex(1e-3, math.copysign(ratio, w_e) * 1e-3)
        c2 = slip_coupling(s2, e, w_e, wc, 10.0, 0.1, 1e-4)
    assert abs(c2) < 1e-15
