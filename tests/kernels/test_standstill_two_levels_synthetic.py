"""The standstill R1 identification at two current levels
(kernels/r1_standstill.py, the controller's block), on hand-made records and a synthetic machine.

The synthetic stator voltage along a DC current ``i`` is ``R1 i + u0 + sigma_L1 di/dt + (M/L2)
dpsi/dt`` with a first-order rotor flux ``T2 dpsi/dt = M i - psi``: a constant residual ``u0``
(what a dead-time compensation leaves along the current at standstill) that one level reads
as resistance. The harness sets the current from what the test asks (``m.dc_boost``) and keeps
the speed reference at zero while the test holds it (``m.dc_busy``), as the drive's stages do.
Checks that could fail independently of the drive: R1 and ``u0`` from two levels from any
T2_hat within +-40 %, the one-level value ``R1 + u0/I`` the difference removes, the hold, and
the status when a level could not complete; and the online scale's start from the residual
(kernels/inverter_scale.py ``start_from_identified``), against the per-phase error's geometry.
"""

import math

import numpy as np
import pytest

from imdrive.kernels.ifoc import CONTROL_PARAMS, CONTROL_STATE, standstill_compensation
from imdrive.kernels.inverter import clarke
from imdrive.kernels.inverter_scale import start_from_identified
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.r1_standstill import r1_standstill
from imdrive.kernels.records import new_record

TS = 1e-4
R1, U0, I0 = 0.6, 1.5, 4.0  # ohm, V (the residual along the current), A (magnetising)
M, LL = 0.2, 0.008  # H
L2 = M + LL
T2 = L2 / 0.8  # the plant's rotor time constant, s (R2 = 0.8 ohm)


def _identify(t2_hat_ratio=1.0, levels=2, magnetise_s=0.5, hold_T2=16.0):
    """Run the synthetic standstill test; the speed reference leaves zero at ``magnetise_s``
    of its profile (later by the time held). Returns the records and the time it left zero."""
    T2_hat = t2_hat_ratio * T2
    p = new_record(
        CONTROL_PARAMS, R1_dc_min=0.1, R1_dc_max=5.0, R1_dc=True, R1_dc_settle=T2_hat,
        R1_dc_block=0.25 * T2_hat, R1_dc_nT2=3.5, R1_dc_levels=levels, R1_dc_boost=-0.4,
        R1_dc_hold=hold_T2 * T2_hat,
    )[0]  # fmt: skip
    m = new_record(
        MODEL_STATE, R1_hat=0.9 * R1, R2_hat=L2 / T2_hat, Ll1_hat=LL, Ll2_hat=LL, M_hat=M
    )[0]
    s = np.zeros(1, dtype=CONTROL_STATE)[0]
    sigma_L1 = (M + LL) - M * M / L2
    psi, i_prev, t, t_hold = 0.0, 0.0, 0.0, 0.0
    left_at = None
    while t < magnetise_s + 3.0:
        w_ref = 0.0 if t - t_hold < magnetise_s else 1.0
        if w_ref != 0.0 and m["dc_busy"] and t_hold < m["dc_hold_max"]:
            t_hold += TS
            w_ref = 0.0
        if w_ref != 0.0 and left_at is None:
            left_at = t
        i = I0 * (1.0 + m["dc_boost"])
        dpsi = (M * i - psi) / T2
        v = R1 * i + U0 + sigma_L1 * (i - i_prev) / TS + (M / L2) * dpsi
        r1_standstill(p, m, s, v, 0.0, i_prev, 0.0, i, 0.0, w_ref, 0.0, TS)
        psi += dpsi * TS
        i_prev = i
        t += TS
        if left_at is not None and t > left_at + 0.01:
            break
    return m, s, left_at


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@pytest.mark.parametrize("t2_hat_ratio", [1 / 1.4, 1.0, 1 / 0.6])  # R2_hat(0) 1.4, 1, 0.6 R2
def test_two_levels_identify_R1_and_the_residual(t2_hat_ratio):
    m, s, left_at = _identify(t2_hat_ratio)
    assert s["dc_status"] == 1.0
    assert m["R1_hat"] == pytest.approx(R1, rel=0.01)
    assert m["u0_id"] == pytest.approx(U0, rel=0.02)  # along the current, at the second level
    assert m["i_id"] == pytest.approx(I0, rel=1e-9)
    assert m["ie_new"] and not m["R1_id"]  # R1_hat holds no residual: no share to give back
    assert m["dc_boost"] == 0.0 and not m["dc_busy"]
    # the cost: the reference waited past the 0.5 s magnetisation, two build-ups of 3.5 T2
    # and their windows, less than the hold's bound
    assert 0.5 < left_at < 16.0 * t2_hat_ratio * T2
    assert left_at == pytest.approx(2 * 3.5 * T2 + 0.2, abs=3 * T2)


def test_one_level_reads_the_residual_as_resistance():
    m, s, _ = _identify(levels=1, magnetise_s=1.5)  # 3.5 T2 = 0.91 s and a window
    assert s["dc_status"] == 1.0
    assert m["R1_hat"] == pytest.approx(R1 + U0 / I0, rel=0.01)  # 1.63 R1
    assert m["R1_id"] and not m["ie_new"]


def test_without_its_hold_the_second_level_says_it_could_not():
    # no hold and 1.3 s: level A (3.5 T2 = 0.91 s, then its window) completes, level B not:
    # R1_hat is what one level would read at level A's current, status 3
    m, s, left_at = _identify(magnetise_s=1.3, hold_T2=0.0)
    assert left_at == pytest.approx(1.3, abs=2 * TS)
    assert s["dc_status"] == 3.0
    assert m["R1_hat"] == pytest.approx(R1 + U0 / (0.6 * I0), rel=0.01)
    assert m["R1_id"] and not m["ie_new"]
    m, s, _ = _identify(magnetise_s=0.5, hold_T2=0.0)  # nor level A
    assert s["dc_status"] == 2.0
    assert m["R1_hat"] == 0.9 * R1


@pytest.mark.parametrize("theta", [0.0, 0.4, math.pi / 6])
@pytest.mark.parametrize(("dk0", "ratio"), [(0.0, 1.25), (0.1, 0.8)])
def test_the_scale_starts_where_the_compensation_leaves_no_residual(theta, dk0, ratio):
    # a standstill current at angle theta, the per-phase error u sgn(i_x) and its
    # compensation at (1 + dk0) u_c: the residual along the current is what the test reads
    u_c = 1.2
    i_a = 5.0 * math.cos(theta)
    i_b = 5.0 * math.sin(theta)
    phases = [math.cos(theta - k * 2 * math.pi / 3) for k in range(3)]
    e_a, e_b = clarke(*(np.sign(x) for x in phases))  # the error per volt of the device
    s = np.zeros(1, dtype=CONTROL_STATE)[0]
    s["ie_dk"] = dk0
    dv_a, dv_b = (1.0 + dk0) * u_c * e_a, (1.0 + dk0) * u_c * e_b  # the compensation applied
    standstill_compensation(s, dv_a, dv_b, i_a, i_b, 0.0)
    left = (ratio * u_c - (1.0 + dk0) * u_c) * (e_a * i_a + e_b * i_b) / 5.0
    m = new_record(MODEL_STATE, u0_id=left, i_id=5.0, ie_new=True)[0]
    start_from_identified(s, m)
    assert 1.0 + s["ie_dk"] == pytest.approx(ratio, rel=1e-9)
    assert not m["ie_new"]
