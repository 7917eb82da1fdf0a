"""The phase current's deviation at its leg's commutations on the switching bridge
(:func:`imdrive.kernels.ifoc.commutation_ripple`) against the carrier period integrated
directly, and the dead-time compensation that follows the loss's shape it gives."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imdrive.kernels.ifoc import (
    CONTROL_PARAMS,
    _bridge_loss_sign,
    commutation_ripple,
    dead_time_feedforward,
)
from imdrive.kernels.inverter import clarke, duty_cycles, phase_values
from imdrive.kernels.records import new_record

VDC = 311.127
TS = 1e-4
SIGMA_L1 = 0.00394  # Table IV's sigma L1, H


def _integrated(v_alpha, v_beta, n=200_000):
    """Each phase current's deviation from its value at the period's start, at its leg's
    turn-on, from the pole waveforms of the symmetric carrier (low at both ends, leg x high
    over [(1 - d_x) Ts/2, (1 + d_x) Ts/2]) integrated over a fine grid, A."""
    d = np.array(duty_cycles(v_alpha, v_beta, VDC))
    t = (np.arange(n) + 0.5) * TS / n
    on = (t[None, :] >= (1 - d[:, None]) * TS / 2) & (t[None, :] <= (1 + d[:, None]) * TS / 2)
    v_pole = VDC * on
    v_xn = v_pole - v_pole.mean(axis=0)  # the phase voltage, the neutral's share removed
    di = np.cumsum(v_xn - v_xn.mean(axis=1, keepdims=True), axis=1) * (TS / n) / SIGMA_L1
    k_on = np.clip(((1 - d) * TS / 2 / (TS / n)).astype(int) - 1, 0, n - 1)
    return np.abs(di[np.arange(3), k_on])


@pytest.mark.parametrize(
    ("mag", "angle_deg"), [(19.6, 90.0), (19.6, 17.0), (60.0, 140.0), (150.0, -75.0), (5.0, 3.0)]
)
def test_deviation_at_the_commutations_matches_the_integrated_period(mag, angle_deg):
    v = mag * complex(math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg)))
    got = np.array(commutation_ripple(v.real, v.imag, VDC, VDC * TS / SIGMA_L1))
    assert got == pytest.approx(_integrated(v.real, v.imag), abs=2e-3)


def test_table_iv_at_a_tenth_of_rated_speed_no_load():
    # 0.1 of the rated speed, no load: about 20 V along q, the current along d; at phase a's
    # zero crossing its voltage is at its peak. The deviation there is about 0.11 A (measured
    # on the bridge: the dead-time loss is 0 inside |i_a| < 0.1 A and whole outside), half
    # the 0.2 A band of the fixed compensation
    r = commutation_ripple(19.6, 0.0, VDC, VDC * TS / SIGMA_L1)
    assert r[0] == pytest.approx(0.113, abs=0.005)


def _params(ripple):
    return new_record(
        CONTROL_PARAMS, dtc_u=5.0, dtc_band=0.2, dtc_ripple=ripple, v_max=VDC / math.sqrt(3.0)
    )[0]


@pytest.mark.parametrize(
    ("i_a", "share"),
    [
        (0.12, 1.0),  # past the ripple at the commutations (0.113 A): the whole loss
        (0.0, 0.0),  # the ripple straddles zero: no loss, no compensation
        (-0.01, 0.0),
        (0.03, None),  # on the edge, smooth over a quarter of the 0.2 A band
        (-0.2, -1.0),
    ],
)
def test_the_compensation_follows_the_bridge_loss_shape(i_a, share):
    # phase a near zero at its voltage peak (0.1 of the rated speed, no load on Table IV);
    # phases b and c far from zero
    i_alpha = i_a
    i_beta = 6.0
    ia, ib, ic = phase_values(i_alpha, i_beta)
    assert ia == pytest.approx(i_a)
    if share is None:  # centred at delta - 0.05 A, so whole from delta on
        delta = commutation_ripple(19.6, 0.0, VDC, VDC * TS / SIGMA_L1)[0]
        share = 0.5 * (1.0 + (i_a - (delta - 0.05)) / 0.05)
        assert 0.0 < share < 1.0
    got = dead_time_feedforward(_params(VDC * TS / SIGMA_L1), i_alpha, i_beta, 19.6, 0.0)
    want = clarke(share * 5.0, math.copysign(5.0, ib), math.copysign(5.0, ic))
    assert got == pytest.approx(want, abs=1e-12)
    # the fixed band's sign model: a share i_a / 0.2 of the loss inside its band
    fixed = dead_time_feedforward(_params(0.0), i_alpha, i_beta, 19.6, 0.0)
    share_fixed = min(max(i_a / 0.2, -1.0), 1.0)
    assert fixed == pytest.approx(
        clarke(share_fixed * 5.0, math.copysign(5.0, ib), math.copysign(5.0, ic)), abs=1e-12
    )


def test_far_from_zero_the_shapes_agree_to_the_bit():
    args = (3.0, 6.0, 19.6, 0.0)
    assert dead_time_feedforward(_params(VDC * TS / SIGMA_L1), *args) == dead_time_feedforward(
        _params(0.0), *args
    )


def _table_params(ripple, i_nodes, u_nodes):
    p = _params(ripple)
    p["dtc_u"] = 0.0  # the identified table replaces the assumed dead time
    p["ie_n"] = len(i_nodes)
    p["ie_i"][: len(i_nodes)] = i_nodes
    p["ie_u"][: len(u_nodes)] = u_nodes
    return p


@pytest.mark.parametrize("i_a", [0.12, 0.0, -0.01, 0.03, -0.2, 0.5, 3.0])
def test_an_identified_table_keeps_the_bridge_loss_shape(i_a):
    # a commissioned drive: the ideal table (5 V reached at the 0.2 A band) on the switching
    # bridge gives the ripple's shape with the table's magnitude, exactly the sign model's
    args = (i_a, 6.0, 19.6, 0.0)
    with_table = _table_params(VDC * TS / SIGMA_L1, [0.0, 0.2, 40.0], [0.0, 5.0, 5.0])
    assert dead_time_feedforward(with_table, *args) == pytest.approx(
        dead_time_feedforward(_params(VDC * TS / SIGMA_L1), *args), abs=1e-12
    )
    # a measured table whose loss grows with the current (an on-state slope): the magnitude
    # is the table's at the phase current, the shape the ripple's
    grows = _table_params(VDC * TS / SIGMA_L1, [0.0, 0.1, 10.0], [0.0, 4.0, 6.0])
    got = dead_time_feedforward(grows, *args)
    ia, ib, ic = phase_values(i_a, 6.0)
    r = commutation_ripple(19.6, 0.0, VDC, VDC * TS / SIGMA_L1)
    assert r[0] > 0.1  # phase a's ripple exceeds the table's first node
    mags = [np.interp(max(abs(x), 0.1), [0.0, 0.1, 10.0], [0.0, 4.0, 6.0]) for x in (ia, ib, ic)]
    signs = [_bridge_loss_sign(x, rx, 0.2) for x, rx in zip((ia, ib, ic), r, strict=True)]
    want = clarke(*(sg * mg for sg, mg in zip(signs, mags, strict=True)))
    assert got == pytest.approx(want, abs=1e-9)
    # without the ripple (the average inverter model) the table alone, as before
    plain = _table_params(0.0, [0.0, 0.2, 40.0], [0.0, 5.0, 5.0])
    share = min(max(ia / 0.2, -1.0), 1.0)
    assert dead_time_feedforward(plain, *args) == pytest.approx(
        clarke(share * 5.0, math.copysign(5.0, ib), math.copysign(5.0, ic)), abs=1e-12
    )
