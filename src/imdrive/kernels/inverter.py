"""Voltage-source inverter: the average-value model and a switching two-level bridge.

The inverter turns the voltage reference the controller holds over one control period into the
voltage the machine sees during that period.

Average-value model (``INV_AVERAGE``)
    One segment per period: the reference limited to the linear range of space-vector
    modulation, ``|v| <= Vdc/sqrt(3)``, direction kept. Dead time and device drops enter in
    averaged form: each phase's pole voltage is lowered by ``sgn_b(i_x) (t_d f_sw Vdc + V_drop)``
    with ``sgn_b`` a sign that is linear inside ``|i| < i_band`` (smooth at the current's zero).

Switching model (``INV_SWITCHING``)
    A two-level, three-leg bridge with a symmetric triangular carrier whose period is the control
    period (regular sampling, single update: ``Ts = 1/f_sw``) and min-max zero-sequence injection
    (equivalent to SVPWM). Leg ``x`` has duty cycle ``d_x = 1/2 + (v_x + v_0)/Vdc_meas`` with
    ``v_0 = -(max v + min v)/2``; its gate is high on ``[(1 - d_x) Ts/2, (1 + d_x) Ts/2)``. The
    engine integrates the plant from one switching instant to the next, so every edge is exact.

    Dead time ``t_d``: at each gate change both switches of the leg are off for ``t_d``, and the
    pole voltage is set by the phase current's sign, taken at the instant the dead time starts:
    ``i_x > 0`` (out of the leg) clamps the pole low through the lower diode, ``i_x < 0`` high
    through the upper one. A gate change towards that state is immediate; the other way the
    transition is delayed by ``t_d``. A gate change during a pending dead time cancels it (the
    incoming switch never turned on). A current that crosses zero *inside* a dead time keeps the
    sign it had at its start: in a real bridge the pole then floats at the back-EMF until the
    next edge; the error is bounded by ``t_d Vdc`` volt-seconds per such crossing. Device drop
    ``V_drop``: the conducting device lowers the pole voltage by ``sgn(i_x) V_drop``, the sign
    taken at the start of each segment.

The phase voltages of the star-connected machine are the Clarke transform of the pole voltages
(the zero sequence does not reach an isolated neutral)::

    v_alpha = (2/3) (v_a - (v_b + v_c)/2),   v_beta = (v_b - v_c) / sqrt(3)
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.kernels.jit import njit
from imdrive.kernels.records import f8, i8, record_dtype

INV_AVERAGE = 0
INV_SWITCHING = 1
MAX_SEGMENTS = 8  # of the average model's segment arrays
MAX_EVENTS = 16  # gate commands and delayed transitions per period of the switching model
INVERTER_CODES = {"average": INV_AVERAGE, "switching": INV_SWITCHING}

SQRT3 = math.sqrt(3.0)

#: Parameters of the inverter.
INVERTER_PARAMS = record_dtype(
    [
        ("Vdc", f8),  # DC-link voltage, V
        ("model", i8),  # INV_AVERAGE or INV_SWITCHING
        ("t_d", f8),  # dead time, s
        ("v_drop", f8),  # forward drop of the conducting device, V
        ("i_band", f8),  # current band of the averaged model's smooth sign, A
        ("f_sw", f8),  # carrier frequency, Hz (the switching model runs one period per Ts)
    ]
)

#: State of the switching model carried from one period to the next.
INVERTER_STATE = record_dtype(
    [
        ("gate", f8, (3,)),  # gate command of each leg at the end of the period (0 low, 1 high)
        ("pole", f8, (3,)),  # pole state of each leg (0 low, 1 high)
        ("pend_t", f8, (3,)),  # pending (dead-time) transition, time into the next period, s
        ("pend_s", f8, (3,)),  # the state it goes to
        ("v_applied_ab", np.complex128),  # period-average voltage applied over the last period, V
    ]
)

#: Log fields written by the engine: the period-average voltage applied at the terminals and
#: the controller's voltage reference of the sample, V.
LOG_FIELDS = ("v_alpha", "v_beta", "v_ref_alpha", "v_ref_beta")


@njit(cache=True)
def limit_magnitude(v_alpha, v_beta, v_max):
    """Scale ``(v_alpha, v_beta)`` down to magnitude ``v_max`` if longer; direction is kept."""
    mag = math.sqrt(v_alpha * v_alpha + v_beta * v_beta)
    if mag > v_max:
        k = v_max / mag
        return v_alpha * k, v_beta * k
    return v_alpha, v_beta


@njit(cache=True)
def phase_values(x_alpha, x_beta):
    """Phase quantities ``(x_a, x_b, x_c)`` of a space vector (amplitude-invariant Clarke)."""
    return x_alpha, -0.5 * x_alpha + 0.5 * SQRT3 * x_beta, -0.5 * x_alpha - 0.5 * SQRT3 * x_beta


@njit(cache=True)
def clarke(x_a, x_b, x_c):
    """Space vector ``(alpha, beta)`` of three phase quantities (zero sequence dropped)."""
    return (2.0 / 3.0) * (x_a - 0.5 * (x_b + x_c)), (x_b - x_c) / SQRT3


@njit(cache=True)
def smooth_sign(i, band):
    """Sign of ``i``, linear inside ``|i| < band`` (``band = 0``: the plain sign, 0 at 0)."""
    if band > 0.0:
        return min(max(i / band, -1.0), 1.0)
    if i > 0.0:
        return 1.0
    if i < 0.0:
        return -1.0
    return 0.0


@njit(cache=True)
def pole_error(p, i_alpha, i_beta, Ts):
    """Averaged dead-time and device-drop error of the applied voltage, ``(alpha, beta)``, V.

    Per phase ``-sgn_b(i_x) (t_d f_sw Vdc + V_drop)``, transformed to the stationary frame.
    """
    ia, ib, ic = phase_values(i_alpha, i_beta)
    u = p.t_d * p.f_sw * p.Vdc + p.v_drop
    ea = -smooth_sign(ia, p.i_band) * u
    eb = -smooth_sign(ib, p.i_band) * u
    ec = -smooth_sign(ic, p.i_band) * u
    return clarke(ea, eb, ec)


@njit(cache=True)
def inverter_segments(p, v_ref_alpha, v_ref_beta, i_alpha, i_beta, Ts, seg_dt, seg_va, seg_vb):
    """Voltage segments the machine sees over one period of the average-value model.

    Parameters
    ----------
    p : INVERTER_PARAMS record
    v_ref_alpha, v_ref_beta : float
        Voltage reference from the controller, stationary frame, V.
    i_alpha, i_beta : float
        Stator current at the start of the period, A (sign of the averaged dead-time error).
    Ts : float
        Control period, s.
    seg_dt, seg_va, seg_vb : float64[MAX_SEGMENTS]
        Outputs: duration (s) and voltage (V) of each segment.

    Returns
    -------
    int
        Number of segments written.
    """
    v_max = p.Vdc / SQRT3
    va, vb = limit_magnitude(v_ref_alpha, v_ref_beta, v_max)
    seg_dt[0] = Ts
    if p.t_d > 0.0 or p.v_drop > 0.0:
        ea, eb = pole_error(p, i_alpha, i_beta, Ts)
        seg_va[0] = va + ea
        seg_vb[0] = vb + eb
    else:  # untouched, so the ideal model stays bit for bit what it was
        seg_va[0] = va
        seg_vb[0] = vb
    return 1


@njit(cache=True)
def duty_cycles(v_alpha, v_beta, Vdc_meas):
    """Duty cycles of the three legs for reference ``(v_alpha, v_beta)`` (min-max injection).

    ``Vdc_meas`` is the DC-link voltage the controller measures; duties are clipped to [0, 1].
    """
    xa, xb, xc = phase_values(v_alpha, v_beta)
    v0 = -0.5 * (max(xa, xb, xc) + min(xa, xb, xc))
    g = 1.0 / Vdc_meas  # one division instead of three
    da = min(max(0.5 + (xa + v0) * g, 0.0), 1.0)
    db = min(max(0.5 + (xb + v0) * g, 0.0), 1.0)
    dc = min(max(0.5 + (xc + v0) * g, 0.0), 1.0)
    return da, db, dc


@njit(cache=True)
def gate_commands(s, d, Ts, ev_t, ev_leg, ev_state, advance=0.0):
    """Gate changes of one carrier period, in time order (writes the ``ev_*`` arrays).

    ``s`` is the INVERTER_STATE (its ``gate`` is the command at the end of the last period and
    becomes this period's final command), ``d`` the three duty cycles. ``advance`` (s) moves
    both commands of every switching leg earlier, the pulse kept whole (a leg's advance is at
    most the time before its turn-on): the controller's dead-time compensation, which
    widens the pulses the dead time narrows, moves them back to where the dead time's delay
    of every commanded edge by ``t_d/2`` on the average would otherwise put their centres
    (:func:`imdrive.kernels.ifoc.dead_time_advance`). Returns the count.
    """
    n = 0
    for x in range(3):
        g = s.gate[x]
        if d[x] >= 1.0:
            if g != 1.0:  # high all period
                ev_t[n] = 0.0
                ev_leg[n] = x
                ev_state[n] = 1.0
                n += 1
            s.gate[x] = 1.0
        elif d[x] <= 0.0:
            if g != 0.0:  # low all period
                ev_t[n] = 0.0
                ev_leg[n] = x
                ev_state[n] = 0.0
                n += 1
            s.gate[x] = 0.0
        else:
            if g != 0.0:  # the last period ended high: the carrier starts low
                ev_t[n] = 0.0
                ev_leg[n] = x
                ev_state[n] = 0.0
                n += 1
            t_on = (1.0 - d[x]) * 0.5 * Ts
            a = min(advance, t_on)
            ev_t[n] = t_on - a
            ev_leg[n] = x
            ev_state[n] = 1.0
            n += 1
            ev_t[n] = (1.0 + d[x]) * 0.5 * Ts - a
            ev_leg[n] = x
            ev_state[n] = 0.0
            n += 1
            s.gate[x] = 0.0
    # insertion sort by time (stable: a leg's own commands keep their order)
    for a in range(1, n):
        t = ev_t[a]
        lg = ev_leg[a]
        st = ev_state[a]
        b = a - 1
        while b >= 0 and ev_t[b] > t:
            ev_t[b + 1] = ev_t[b]
            ev_leg[b + 1] = ev_leg[b]
            ev_state[b + 1] = ev_state[b]
            b -= 1
        ev_t[b + 1] = t
        ev_leg[b + 1] = lg
        ev_state[b + 1] = st
    return n


@njit(cache=True)
def apply_command(p, s, x, new_gate, i_x, t):
    """A gate change of leg ``x`` at time ``t`` with phase current ``i_x`` (dead-time logic).

    Cancels a pending transition of the leg; the pole takes the dead-time state set by the
    current's sign, and reaches ``new_gate`` at once if that is the same state, else after
    ``t_d`` (a pending transition).
    """
    s.pend_t[x] = -1.0
    if p.t_d <= 0.0:
        s.pole[x] = new_gate
        return
    dead = 0.0 if i_x >= 0.0 else 1.0  # the freewheeling diode's state
    s.pole[x] = dead
    if dead != new_gate:
        s.pend_t[x] = t + p.t_d
        s.pend_s[x] = new_gate


@njit(cache=True)
def pole_voltages_ab(p, s, Vdc, i_alpha, i_beta):
    """Stator voltage ``(alpha, beta)`` of the bridge's present pole states, V."""
    va = (s.pole[0] - 0.5) * Vdc
    vb = (s.pole[1] - 0.5) * Vdc
    vc = (s.pole[2] - 0.5) * Vdc
    if p.v_drop > 0.0:
        ia, ib, ic = phase_values(i_alpha, i_beta)
        va -= smooth_sign(ia, 0.0) * p.v_drop
        vb -= smooth_sign(ib, 0.0) * p.v_drop
        vc -= smooth_sign(ic, 0.0) * p.v_drop
    return clarke(va, vb, vc)
