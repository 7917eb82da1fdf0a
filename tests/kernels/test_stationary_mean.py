"""``stationary_mean_removed``: the flux error less its mean in the stationary frame.

A constant error of the measured current (the sensors' offsets) puts a constant into the
detection's flux error in the stationary frame: in the controller's frame a phasor turning at
the stator frequency. The injection's R2 signal is an in-phase d-axis sinusoid at the
injection's frequency, whose side bands the schedule keeps away from DC.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from imdrive.kernels.compensator import COMPENSATOR_STATE
from imdrive.kernels.detection import (
    MEAN_CORNER_PER_FILTER,
    MEAN_CORNER_PER_SIDE_BAND,
    stationary_mean_removed,
)

Ts = 1e-4
WC = 15.0  # the detection filter's corner, rad/s


@njit
def _removed(e_dq, theta, w_e, w_i):
    """``stationary_mean_removed`` of a fresh state over the samples of ``e_dq`` (controller's
    frame at the angle ``theta``), turned into the stationary frame and back."""
    state = np.zeros(1, dtype=COMPENSATOR_STATE)
    s = state[0]
    out = np.empty_like(e_dq)
    for k in range(e_dq.shape[0]):
        rot = complex(math.cos(theta[k]), math.sin(theta[k]))  # as r2_tracking.track turns it
        out[k] = stationary_mean_removed(s, e_dq[k] * rot, w_e, w_i, WC, Ts) * rot.conjugate()
    return out


def _corner(w_e, w_i):
    """The mean's corner, rad/s: the side band's share, bounded by the filter's."""
    return min(MEAN_CORNER_PER_SIDE_BAND * abs(abs(w_e) - w_i), MEAN_CORNER_PER_FILTER * WC)


def _in_phase(e_dq, t, w_i, periods):
    """The synchronous detection's in-phase amplitude of e_d over the last whole periods."""
    n = int(round(periods * 2 * math.pi / w_i / Ts))
    return float(np.mean(2.0 * e_dq.real[-n:] * np.sin(w_i * t[-n:])))


def _worst_window(e_dq, t, w_i, windows):
    """The largest in-phase amplitude of one injection period's window over the last
    ``windows`` windows (the law's decisions)."""
    n = int(round(2 * math.pi / w_i / Ts))
    prod = 2.0 * e_dq.real * np.sin(w_i * t)
    return max(
        abs(float(np.mean(prod[len(t) - (j + 1) * n : len(t) - j * n]))) for j in range(windows)
    )


@pytest.mark.parametrize(
    "f_e, f_i, leaks",
    [(10.3, 1.64, True), (-10.3, 1.64, True), (2.5, 4.0, True), (0.0, 1.1, False),
     (47.0, 6.1, True)],
)  # fmt: skip
def test_an_offset_goes_and_the_r2_signal_stays(f_e, f_i, leaks):
    """An offset's constant ``D`` in the stationary frame, 20 times the R2 signal's amplitude
    ``A`` (20 mA through the Aalto machine's R1 and the 15 rad/s filter give about 5 mWb; 1 % of
    R2 is a few tenths of a mWb at the injection's amplitude), plus the R2 signal
    ``A sin(w_i t)`` on d: once settled the detection reads ``A`` to 0.3 %, where without the
    removal the offset's phasor alone reads more than half of ``A`` through some of 20
    windows of one injection period, the law's decisions (0.8-15 times ``A`` measured; none
    at ``f_e = 0``, where it is constant on d), and with it less than 2 % (measured: below
    1e-4)."""
    w_e, w_i = 2 * math.pi * f_e, 2 * math.pi * f_i
    A = 1e-3
    D = 20 * A * complex(0.6, -0.8)
    settle = 12.0 / _corner(w_e, w_i)
    t = np.arange(int(round((settle + 20 * 2 * math.pi / w_i) / Ts))) * Ts
    theta = w_e * t
    phasor = D * np.exp(-1j * theta)
    out = _removed(A * np.sin(w_i * t) + phasor, theta, w_e, w_i)
    assert _in_phase(out, t, w_i, 20) == pytest.approx(A, rel=3e-3)
    assert _worst_window(out - A * np.sin(w_i * t), t, w_i, 20) < 2e-2 * A
    raw = _worst_window(phasor, t, w_i, 20) / A
    assert raw > 0.5 if leaks else raw < 1e-3


@pytest.mark.parametrize("f_e, f_i, sign", [(10.0, 1.5, 1), (10.0, 1.5, -1), (0.3, 2.0, 1)])
def test_the_side_bands_keep_their_phase(f_e, f_i, sign):
    """A stationary-frame tone at either side band ``w_e +- w_i`` keeps its gain to 0.2 % and
    its phase to ``atan(MEAN_CORNER_PER_SIDE_BAND)`` (1.1 degrees) at the nearer one, less at
    the other."""
    w_e, w_i = 2 * math.pi * f_e, 2 * math.pi * f_i
    w_sb = w_e + sign * w_i
    w_h = _corner(w_e, w_i)
    t = np.arange(int(round((10.0 / w_h + 10 * 2 * math.pi / abs(w_sb)) / Ts))) * Ts
    theta = w_e * t
    tone_ab = np.exp(1j * w_sb * t)
    out_ab = _removed(tone_ab * np.exp(-1j * theta), theta, w_e, w_i) * np.exp(1j * theta)
    n = int(round(5 * 2 * math.pi / abs(w_sb) / Ts))
    h = np.mean(out_ab[-n:] / tone_ab[-n:])
    assert abs(h) == pytest.approx(1.0, abs=2e-3)
    bound = math.atan(w_h / abs(w_sb))
    assert abs(np.angle(h)) <= bound * 1.05 + 1e-4
    assert bound <= math.atan(MEAN_CORNER_PER_SIDE_BAND) + 1e-12
