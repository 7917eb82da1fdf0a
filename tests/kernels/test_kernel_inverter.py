"""The inverter kernels alone, on hand-made records (kernels/inverter.py).

Average model: the voltage limit of linear space-vector modulation, the averaged dead-time and
device-drop error against its per-phase formula, the segment it hands the plant. Switching
bridge: duty cycles (min-max injection) against the carrier comparison, the gate commands'
order, the dead-time logic of a gate change by the current's sign.
"""

import math

import numpy as np
import pytest

from imdrive.kernels.inverter import (
    INVERTER_PARAMS,
    INVERTER_STATE,
    MAX_EVENTS,
    MAX_SEGMENTS,
    apply_command,
    clarke,
    duty_cycles,
    gate_commands,
    inverter_segments,
    limit_magnitude,
    phase_values,
    pole_error,
    pole_voltages_ab,
)
from imdrive.kernels.records import new_record

VDC = 540.0
TS = 1e-4


def _params(**kw):
    values = {"Vdc": VDC, "f_sw": 1.0 / TS, **kw}
    return new_record(INVERTER_PARAMS, **values)[0]


def _state():
    return np.zeros(1, dtype=INVERTER_STATE)[0]


def test_clarke_inverts_phase_values():
    for a, b in [(1.0, 0.0), (0.3, -2.0), (-5.0, 7.5)]:
        assert clarke(*phase_values(a, b)) == pytest.approx((a, b), abs=1e-12)
    assert sum(phase_values(3.0, -1.0)) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("v", [(100.0, 50.0), (-300.0, 400.0), (0.0, 0.0)])
def test_limit_magnitude_keeps_short_vectors_and_direction(v):
    v_max = 311.0
    a, b = limit_magnitude(v[0], v[1], v_max)
    mag = math.hypot(*v)
    if mag <= v_max:
        assert (a, b) == v
    else:
        assert math.hypot(a, b) == pytest.approx(v_max, rel=1e-12)
        assert math.atan2(b, a) == pytest.approx(math.atan2(v[1], v[0]), abs=1e-12)


@pytest.mark.parametrize("band", [0.0, 0.5])
@pytest.mark.parametrize("i", [(10.0, 0.0), (-3.0, 4.0), (0.2, -0.1), (0.0, 0.0)])
def test_pole_error_is_the_per_phase_formula_in_the_stationary_frame(i, band):
    p = _params(t_d=2e-6, v_drop=1.5, i_band=band)
    u = 2e-6 * (1.0 / TS) * VDC + 1.5  # t_d f_sw Vdc + V_drop, V
    phases = phase_values(*i)
    want = [-(np.clip(x / band, -1.0, 1.0) if band > 0 else np.sign(x)) * u for x in phases]
    ea, eb = pole_error(p, i[0], i[1], TS)
    va = (2.0 / 3.0) * (want[0] - 0.5 * (want[1] + want[2]))
    vb = (want[1] - want[2]) / math.sqrt(3.0)
    assert (ea, eb) == pytest.approx((va, vb), abs=1e-12)


def test_pole_error_opposes_the_current_with_magnitude_four_thirds_u():
    """A current along phase a, well outside the band: signs (+, -, -) give the classic
    volt-second loss ``(4/3) u`` against the current."""
    p = _params(t_d=3e-6, i_band=0.1)
    u = 3e-6 * (1.0 / TS) * VDC
    ea, eb = pole_error(p, 10.0, 0.0, TS)
    assert ea == pytest.approx(-4.0 / 3.0 * u, rel=1e-12)
    assert eb == pytest.approx(0.0, abs=1e-12)


def test_average_segment_is_the_limited_reference_plus_the_pole_error():
    seg_dt, seg_va, seg_vb = (np.zeros(MAX_SEGMENTS) for _ in range(3))
    ideal = _params()
    assert inverter_segments(ideal, 500.0, 0.0, 5.0, 0.0, TS, seg_dt, seg_va, seg_vb) == 1
    assert seg_dt[0] == TS
    assert (seg_va[0], seg_vb[0]) == pytest.approx((VDC / math.sqrt(3.0), 0.0), rel=1e-12)
    real = _params(t_d=2e-6, v_drop=1.0, i_band=0.2)
    inverter_segments(real, 100.0, 50.0, 5.0, -2.0, TS, seg_dt, seg_va, seg_vb)
    ea, eb = pole_error(real, 5.0, -2.0, TS)
    assert (seg_va[0], seg_vb[0]) == (100.0 + ea, 50.0 + eb)


@pytest.mark.parametrize("v", [(200.0, 0.0), (-120.0, 250.0), (0.0, 0.0), (300.0, 10.0)])
def test_duty_cycles_average_to_the_reference(v):
    """The legs' average pole voltages ``(d_x - 1/2) Vdc`` give back the reference through
    Clarke (the zero sequence drops out), within the linear range."""
    d = duty_cycles(v[0], v[1], VDC)
    assert all(0.0 <= x <= 1.0 for x in d)
    poles = [(x - 0.5) * VDC for x in d]
    assert clarke(*poles) == pytest.approx(v, abs=1e-9)
    # min-max injection centres the duties: max + min = 1
    assert max(d) + min(d) == pytest.approx(1.0, abs=1e-12)


def test_duty_cycles_clip_beyond_the_dc_link():
    d = duty_cycles(2.0 * VDC, 0.0, VDC)
    assert d[0] == 1.0 and d[1] == d[2] == 0.0


def test_gate_commands_are_sorted_and_centred_on_the_carrier():
    s = _state()
    d = np.array([0.8, 0.5, 0.2])
    ev_t, ev_leg, ev_state = (np.zeros(MAX_EVENTS) for _ in range(3))
    n = gate_commands(s, d, TS, ev_t, ev_leg, ev_state)
    assert n == 6
    assert np.all(np.diff(ev_t[:n]) >= 0.0)
    for x in range(3):
        mine = [(ev_t[j], ev_state[j]) for j in range(n) if ev_leg[j] == x]
        (t_on, s_on), (t_off, s_off) = mine
        assert (s_on, s_off) == (1.0, 0.0)
        assert t_on == pytest.approx((1.0 - d[x]) * TS / 2)
        assert t_off - t_on == pytest.approx(d[x] * TS)  # high for d_x Ts
    # the widest pulse turns on first and off last
    assert ev_leg[0] == 0 and ev_leg[n - 1] == 0
    assert list(s["gate"]) == [0.0, 0.0, 0.0]


def test_gate_commands_of_a_saturated_leg_and_a_period_that_ended_high():
    s = _state()
    s["gate"][:] = [1.0, 0.0, 1.0]
    ev_t, ev_leg, ev_state = (np.zeros(MAX_EVENTS) for _ in range(3))
    n = gate_commands(s, np.array([1.0, 0.0, 0.5]), TS, ev_t, ev_leg, ev_state)
    events = sorted(zip(ev_t[:n], ev_leg[:n].astype(int), ev_state[:n], strict=True))
    # leg 0 stays high (no event), leg 1 stays low (none), leg 2 starts low then pulses
    assert [e[1] for e in events] == [2, 2, 2]
    assert events[0] == (0.0, 2, 0.0)
    assert list(s["gate"]) == [1.0, 0.0, 0.0]


@pytest.mark.parametrize(
    ("i_x", "new_gate", "pole", "pending"),
    [
        (5.0, 0.0, 0.0, False),  # current out of the leg: lower diode, turning off is at once
        (5.0, 1.0, 0.0, True),  # turning on waits t_d with the pole held low
        (-5.0, 1.0, 1.0, False),  # current into the leg: upper diode, turning on is at once
        (-5.0, 0.0, 1.0, True),  # turning off waits t_d with the pole held high
    ],
)
def test_apply_command_dead_time_by_the_current_sign(i_x, new_gate, pole, pending):
    p = _params(t_d=2e-6)
    s = _state()
    s["pole"][1] = 1.0 - new_gate
    apply_command(p, s, 1, new_gate, i_x, 3e-5)
    assert s["pole"][1] == pole
    if pending:
        assert s["pend_t"][1] == pytest.approx(3e-5 + 2e-6)
        assert s["pend_s"][1] == new_gate
    else:
        assert s["pend_t"][1] == -1.0


def test_apply_command_cancels_a_pending_transition_and_is_ideal_without_dead_time():
    p = _params(t_d=2e-6)
    s = _state()
    apply_command(p, s, 0, 1.0, 5.0, 1e-5)  # pending rise
    assert s["pend_t"][0] > 0
    apply_command(p, s, 0, 0.0, 5.0, 1.1e-5)  # back low before the dead time ended
    assert s["pend_t"][0] == -1.0 and s["pole"][0] == 0.0
    ideal = _params()
    apply_command(ideal, s, 2, 1.0, 5.0, 0.0)
    assert s["pole"][2] == 1.0 and s["pend_t"][2] == -1.0


def test_pole_voltages_of_a_pole_state():
    s = _state()
    s["pole"][:] = [1.0, 0.0, 0.0]  # the active vector along phase a: (2/3) Vdc
    va, vb = pole_voltages_ab(_params(), s, VDC, 0.0, 0.0)
    assert (va, vb) == pytest.approx((2.0 / 3.0 * VDC, 0.0), abs=1e-9)
    s["pole"][:] = [1.0, 1.0, 1.0]  # a zero vector
    assert pole_voltages_ab(_params(), s, VDC, 0.0, 0.0) == pytest.approx((0.0, 0.0), abs=1e-9)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_advance_moves_every_switching_legs_commands_earlier_and_keeps_the_pulse():
    Ts = TS
    s = np.zeros(1, dtype=INVERTER_STATE)[0]
    ev = np.zeros((3, MAX_EVENTS))
    d = np.array([0.5, 0.99, 1.0])  # a leg in the middle, one near the top, one high throughout
    n = gate_commands(s, d, Ts, ev[0], ev[1], ev[2], 2e-6)
    cmds = {(int(ev[1, j]), ev[2, j]): ev[0, j] for j in range(n)}
    # leg a: both commands 2 us early, the pulse as long as commanded
    assert cmds[(0, 1.0)] == pytest.approx(0.25 * Ts - 2e-6, abs=1e-15)
    assert cmds[(0, 0.0)] == pytest.approx(0.75 * Ts - 2e-6, abs=1e-15)
    # leg b turns on 0.5 us after the period's start: moved by that only, the pulse whole
    assert cmds[(1, 1.0)] == pytest.approx(0.0, abs=1e-15)
    assert cmds[(1, 0.0)] - cmds[(1, 1.0)] == pytest.approx(0.99 * Ts, abs=1e-15)
    # leg c is high all period: one command at the start, none moved
    assert cmds[(2, 1.0)] == 0.0 and (2, 0.0) not in cmds
