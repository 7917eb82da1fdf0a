"""The switching bridge over one carrier period: the plant integrated between gate events.

The period's gate commands (:func:`imdrive.kernels.inverter.gate_commands`) and the dead-time
transitions they cause are events in time order; between two events the pole states are
constant and the plant is integrated over that exact interval.
"""

from __future__ import annotations

from numba import njit

from imdrive.kernels.inverter import (
    apply_command,
    duty_cycles,
    gate_commands,
    phase_values,
    pole_voltages_ab,
)
from imdrive.kernels.machine import integrate_segment, integrate_short, stator_current_m


@njit(cache=True)
def switching_period(
    pinv, sinv, pp, x, v_a, v_b, Vdc_meas, R1b, R2b, TL0, Ts, nsub, work, ev, trace
):
    """Integrate the plant over one carrier period of the switching bridge (updates ``x``).

    The gate commands of the period (:func:`imdrive.kernels.inverter.gate_commands`) and the
    dead-time transitions they cause are events in time order; between two events the pole
    states are constant and the plant is integrated over that exact interval. The phase
    current at a command instant (from the integrated state) decides its dead-time
    transition. Returns the period-average voltage applied at the terminals, V.

    ``ev`` is float64[3, MAX_EVENTS] scratch (times, legs, states). ``trace``, float64[n, 3],
    receives ``(t, i_alpha, i_beta)`` at the start of every interval while it has rows (pass a
    zero-row array for none): the current ripple's extremes are at these instants.
    """
    d = duty_cycles(v_a, v_b, Vdc_meas)
    ev_t = ev[0]
    ev_leg = ev[1]
    ev_state = ev[2]
    n = gate_commands(sinv, d, Ts, ev_t, ev_leg, ev_state)
    t = 0.0
    j = 0
    n_tr = 0
    need_current = pinv.v_drop > 0.0 or trace.shape[0] > 0
    short = Ts / (40.0 * nsub)  # intervals up to this long take one RK2 step
    m_sat = -1.0  # |psi_m| of the last saturated solve, the start of the next (saturation)
    acc_a = 0.0
    acc_b = 0.0
    while True:
        t_next = Ts
        kind = 0  # 0: end of period, 1: gate command, 2: dead-time transition
        leg = -1
        for q in range(3):
            if 0.0 <= sinv.pend_t[q] < Ts and sinv.pend_t[q] <= t_next:
                t_next = sinv.pend_t[q]
                kind = 2
                leg = q
        if j < n and ev_t[j] < t_next:
            t_next = ev_t[j]
            kind = 1
            leg = int(ev_leg[j])
        if t_next > t:
            i_s_a = 0.0
            i_s_b = 0.0
            if need_current:  # the device drops' sign, or the trace
                i_s_a, i_s_b, m_sat = stator_current_m(pp, x, m_sat)
            if n_tr < trace.shape[0]:
                trace[n_tr, 0] = t
                trace[n_tr, 1] = i_s_a
                trace[n_tr, 2] = i_s_b
                n_tr += 1
            va, vb = pole_voltages_ab(pinv, sinv, pinv.Vdc, i_s_a, i_s_b)
            if t_next - t <= short:
                m_sat = integrate_short(pp, x, va, vb, R1b, R2b, TL0, t_next - t, m_sat)
            else:
                m_sat = integrate_segment(
                    pp, x, va, vb, R1b, R2b, TL0, t_next - t, nsub, work, m_sat
                )
            acc_a += (t_next - t) * va
            acc_b += (t_next - t) * vb
            t = t_next
        if kind == 0:
            break
        if kind == 1:
            i_leg = 0.0
            if pinv.t_d > 0.0:  # the dead time's direction needs the leg's current
                i_s_a, i_s_b, m_sat = stator_current_m(pp, x, m_sat)
                i_leg = phase_values(i_s_a, i_s_b)[leg]
            apply_command(pinv, sinv, leg, ev_state[j], i_leg, t)
            j += 1
        else:
            sinv.pole[leg] = sinv.pend_s[leg]
            sinv.pend_t[leg] = -1.0
    for q in range(3):  # a dead time running past the period ends in the next one
        if sinv.pend_t[q] >= 0.0:
            sinv.pend_t[q] -= Ts
    return acc_a / Ts, acc_b / Ts
