"""The switching bridge over one carrier period: the plant integrated between gate events.

The period's gate commands (:func:`imdrive.kernels.inverter.gate_commands`) and the dead-time
transitions they cause are events in time order; between two events the pole states are
constant and the plant is integrated over that exact interval.

How a period is integrated (:func:`switching_period`). Over one carrier period (100 us) the
speed, the winding temperatures and hence R1, R2 change by parts in 1e6 or less, so the
electrical equations are integrated with them held: the speed at its value predicted for
mid-period (``w(0) + Ts/2 dw/dt(0)``), the resistances at the period's start. With those
held, the flux equations are linear with constant coefficients, and each interval between
two events is advanced by the Taylor series of that linear system
(:func:`imdrive.kernels.machine.flux_taylor`; third order, :data:`LONG_ORDER`, or second
order for intervals shorter than ``Ts/40``) on the four flux components only. The rest of
the state is integrated once per period from integrals the intervals accumulate by Simpson's
rule on their start, middle and end (the trapezoidal rule on the short ones): the torque
(the speed), the input power, the copper losses (the energies and the temperatures).

Main-flux saturation: the currents are linear in the fluxes when the magnetising ratio
``k = |psi_m|/|psi_x|`` is held (:func:`imdrive.kernels.machine.current_coefficients`; the
coefficients are then linear in ``k``), so each interval holds ``k`` at its value predicted
for the interval's middle (first order in ``|psi_x|`` from the start's slope, from the
start's currents; a short interval holds ``k`` of its start)
and the currents at its end come from the curve's series about the period's start
(:func:`imdrive.kernels.machine.magnetising_ratio`). The curve is solved once a period, at
its end, for the next period's series and the check's current (:data:`CARRY_FIELDS`).
``tests/drive/test_realistic_drive.py`` measures the result against solve_ivp with the switching
instants as breakpoints.
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.kernels.inverter import (
    apply_command,
    duty_cycles,
    gate_commands,
    phase_values,
    pole_voltages_ab,
)
from imdrive.kernels.jit import njit
from imdrive.kernels.machine import (
    THIRD,
    current_coefficients,
    flux_rates,
    flux_taylor,
    load_torque,
    magnetising_ratio_series,
    winding_resistances,
)
from imdrive.kernels.records import f8, record_dtype

#: What the bridge carries from one period to the next (fields of the run loop's scratch
#: record): the magnetising ratio's series about the state a period ended in, the fluxes it
#: belongs to, and that state's stator current (bit for bit what
#: :func:`imdrive.kernels.machine.stator_current` gives), so the saturated curve is solved
#: once a period: for the check after it and the next period's start alike.
CARRY_FIELDS = [
    ("sat_valid", f8),  # 1: the fields below belong to the fluxes sat_sa, ..., sat_rb
    ("sat_sa", f8),  # psi_s_alpha, Wb
    ("sat_sb", f8),
    ("sat_ra", f8),  # psi_r_alpha, Wb
    ("sat_rb", f8),
    ("sat_k", f8),  # the series of :func:`_ratio_series`
    ("sat_k_u", f8),
    ("sat_k_uu", f8),
    ("sat_u0", f8),
    ("sat_xa", f8),
    ("sat_xb", f8),
    ("sat_i_alpha", f8),  # the state's stator current, A
    ("sat_i_beta", f8),
]
CARRY = record_dtype(CARRY_FIELDS)

#: Order of the Taylor step of the intervals longer than ``Ts/(40 nsub)``. Third order: the
#: fourth-order term is below the other errors at these steps (against solve_ivp, the
#: currents of ``tests/drive/test_realistic_drive.py``'s inrush tests moved by under 1e-6 A,
#: within 1.6e-5 A of the reference at most, and the speed within 7e-5 rpm), at 20 fewer
#: operations a step.
LONG_ORDER = 3


@njit(cache=True, inline="always")
def _trace(trace, n_tr, t, isa, isb):
    """Row ``n_tr`` of the current trace ``(t, i_alpha, i_beta)`` while it has rows; the next
    row's index."""
    if n_tr < trace.shape[0]:
        trace[n_tr, 0] = t
        trace[n_tr, 1] = isa
        trace[n_tr, 2] = isb
        return n_tr + 1
    return n_tr


@njit(cache=True, inline="always")
def _currents(c_ss, c_sr, c_rr, sa, sb, ra, rb):
    """Stator and rotor currents ``(i_s_alpha, i_s_beta, i_r_alpha, i_r_beta)`` of the fluxes."""
    return (
        c_ss * sa + c_sr * ra,
        c_ss * sb + c_sr * rb,
        c_sr * sa + c_rr * ra,
        c_sr * sb + c_rr * rb,
    )


@njit(cache=True, inline="always")
def _next_event(sinv, ev_t, ev_leg, j, n, Ts):
    """``(t, kind, leg)`` of the next event: kind 0 the period's end, 1 gate command ``j``,
    2 a pending dead-time transition (which comes first at equal times)."""
    t_next = Ts
    kind = 0
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
    return t_next, kind, leg


@njit(cache=True, inline="always")
def _ratio_series(pp, sa, sb, ra, rb):
    """``(k, dk/du, d2k/du2, u0, x_alpha, x_beta)``: the magnetising ratio as a quadratic in
    ``u = |psi_x|^2`` about the period's start (zeros without saturation); ``psi_x`` and ``k``
    computed as :func:`imdrive.kernels.machine.saturated_currents` does."""
    k = 0.0
    k_u = 0.0
    k_uu = 0.0
    u0 = 0.0
    xa = 0.0
    xb = 0.0
    if pp.saturation:
        xa = sa / pp.Ll1 + ra / pp.Ll2
        xb = sb / pp.Ll1 + rb / pp.Ll2
        u0 = xa * xa + xb * xb
        k, k_u, k_uu = magnetising_ratio_series(pp, math.sqrt(u0))
    return k, k_u, k_uu, u0, xa, xb


@njit(cache=True, inline="always")
def _carried_series(pp, c, sa, sb, ra, rb):
    """:func:`_ratio_series` at the fluxes ``(sa, sb, ra, rb)``: from the carry record ``c``
    when it belongs to them (the last period stored it), else solved."""
    if c.sat_valid == 1.0 and c.sat_sa == sa and c.sat_sb == sb and c.sat_ra == ra:
        if c.sat_rb == rb:
            return c.sat_k, c.sat_k_u, c.sat_k_uu, c.sat_u0, c.sat_xa, c.sat_xb
    return _ratio_series(pp, sa, sb, ra, rb)


@njit(cache=True, inline="always")
def _carry(pp, x, c):
    """Store in ``c`` the series about the state ``x`` the period ended in, and its stator
    current (:func:`imdrive.kernels.machine.saturated_currents`' arithmetic)."""
    sa = x.psi_s_ab.real
    sb = x.psi_s_ab.imag
    ra = x.psi_r_ab.real
    rb = x.psi_r_ab.imag
    k, k_u, k_uu, u0, xa, xb = _ratio_series(pp, sa, sb, ra, rb)
    c.sat_sa, c.sat_sb, c.sat_ra, c.sat_rb = sa, sb, ra, rb
    c.sat_k, c.sat_k_u, c.sat_k_uu, c.sat_u0, c.sat_xa, c.sat_xb = k, k_u, k_uu, u0, xa, xb
    c.sat_i_alpha = (sa - k * xa) / pp.Ll1
    c.sat_i_beta = (sb - k * xb) / pp.Ll1
    c.sat_valid = 1.0


@njit(cache=True, inline="always")
def _apply_event(pinv, sinv, kind, leg, ev_state, j, isa, isb, t):
    """Apply event ``kind`` (1: gate command ``j``, its dead time decided by the leg's current
    from the stator current ``(isa, isb)``, alpha/beta; 2: a dead time's end) at ``t``;
    returns the index of the next gate command."""
    if kind == 1:
        i_leg = 0.0
        if pinv.t_d > 0.0:  # the dead time's direction needs the leg's current
            i_leg = phase_values(isa, isb)[leg]
        apply_command(pinv, sinv, leg, ev_state[j], i_leg, t)
        return j + 1
    sinv.pole[leg] = sinv.pend_s[leg]
    sinv.pend_t[leg] = -1.0
    return j


@njit(cache=True, inline="always")
def _close_period(pp, x, TL0, Ts, R1, R2, w0, dw0, sa, sb, ra, rb, int_Te, int_W, int_is2,
                  int_ir2, e_in):  # fmt: skip
    """The state at the period's end from the fluxes and the period's integrals (the speed
    from the torque's integral, the rotor flux's angle corrected for the speed's change, the
    temperatures from the copper losses, the energies)."""
    inv_J = 1.0 / pp.J  # one division, off the chain through the period's end
    if pp.speed_imposed:
        w1 = w0
        load_int = Ts * (load_torque(pp, TL0, w0) + pp.B * w0)
    else:
        w1p = w0 + (int_Te - Ts * (load_torque(pp, TL0, w0) + pp.B * w0)) * inv_J
        w_mid = 0.5 * (w0 + w1p)
        load_int = Ts * (load_torque(pp, TL0, w_mid) + pp.B * w_mid)
        w1 = w0 + (int_Te - load_int) * inv_J
    w_avg = 0.5 * (w0 + w1)
    # the error of the speed's linear model: int (w(t) - w0 - t dw0) dt over the period, with
    # w(t) from the torque's double integral; the rotor flux turned n_p times that too little
    if not pp.speed_imposed:
        dth = pp.n_p * ((int_W - 0.5 * Ts * load_int) * inv_J - 0.5 * Ts * Ts * dw0)
        ra, rb = ra - dth * rb, rb + dth * ra
    x.psi_s_ab = complex(sa, sb)
    x.psi_r_ab = complex(ra, rb)
    x.w_m = w1
    x.theta_m += Ts * w_avg
    p_cu1 = 1.5 * R1 * int_is2  # copper losses over the period, J
    p_cu2 = 1.5 * R2 * int_ir2
    if pp.thermal:
        x.theta1 += (pp.Rth1 * p_cu1 - Ts * (x.theta1 - pp.theta_amb)) / pp.tau1
        x.theta2 += (pp.Rth2 * p_cu2 - Ts * (x.theta2 - pp.theta_amb)) / pp.tau2
    x.E_in += 1.5 * e_in
    x.E_cu += p_cu1 + p_cu2
    x.E_em += int_Te * w_avg
    x.E_load += load_int * w_avg


@njit(cache=True, inline="always")
def _period_coefficients(pp, R1, R2, sa, sb, ra, rb, carry):
    """What the period's steps hold: ``(g1, g2, k, dk/du, d2k/du2 / 2, u0, x_alpha, x_beta,
    coefficients)``, the coefficients ``(cs1, csr1, cr1, as0, as1, asr1, ars1, ar0, ar1,
    c_ss, c_sr, c_rr)``.

    Saturated, the current coefficients are linear in the magnetising ratio ``k``
    (``c_ss = g1 - g1^2 k``, ``c_sr = -g1 g2 k``, ``c_rr = g2 - g2^2 k``; ``a = -R c``), so a
    held ``k`` costs one multiply-add per coefficient; ``c_*`` are those of the period's start.
    """
    g1 = 1.0 / pp.Ll1
    g2 = 1.0 / pp.Ll2
    k, k_u, k_uu, u0, xa, xb = _carried_series(pp, carry, sa, sb, ra, rb)
    cs1 = -g1 * g1
    csr1 = -g1 * g2
    cr1 = -g2 * g2
    if pp.saturation:
        c_ss, c_sr, c_rr = g1 + cs1 * k, csr1 * k, g2 + cr1 * k
    else:
        c_ss, c_sr, c_rr = current_coefficients(pp, k)
    co = (cs1, csr1, cr1, -R1 * g1, -R1 * cs1, -R1 * csr1, -R2 * csr1, -R2 * g2, -R2 * cr1,
          c_ss, c_sr, c_rr)  # fmt: skip
    return g1, g2, k, k_u, 0.5 * k_uu, u0, xa, xb, co


@njit(cache=True, inline="always")
def _rates_held(k, co):
    """``(a_ss, a_sr, a_rs, a_rr)`` at a held magnetising ratio ``k`` (``co`` of
    :func:`_period_coefficients`)."""
    return co[3] + co[4] * k, co[5] * k, co[6] * k, co[7] + co[8] * k


@njit(cache=True, inline="always")
def _currents_held(k, g1, g2, co):
    """``(c_ss, c_sr, c_rr)`` at a held magnetising ratio ``k``."""
    return g1 + co[0] * k, co[1] * k, g2 + co[2] * k


@njit(cache=True, inline="always")
def _simpson(h, h3, int_Te, va, vb, Te, Te_m, Te_e, isa, isb, ira, irb, msa, msb, mra, mrb,
             esa, esb, era, erb):  # fmt: skip
    """A step's increments of ``(int_W, int_Te, e_in, int_is2, int_ir2)`` by Simpson's rule on
    its start, middle and end (``h3 = h/3``; ``int_W``'s inner integral quadratic in time)."""
    h6 = 0.5 * h3  # h/6, exactly
    return (
        h * int_Te + h * h6 * (Te + 2.0 * Te_m),
        h6 * (Te + 4.0 * Te_m + Te_e),
        h6 * (va * (isa + 4.0 * msa + esa) + vb * (isb + 4.0 * msb + esb)),
        h6 * (isa * isa + isb * isb + 4.0 * (msa * msa + msb * msb) + esa * esa + esb * esb),
        h6 * (ira * ira + irb * irb + 4.0 * (mra * mra + mrb * mrb) + era * era + erb * erb),
    )


@njit(cache=True, inline="always")
def _trapezoid(h, h3, int_Te, va, vb, Te, Te_e, isa, isb, ira, irb, esa, esb, era, erb):
    """The increments of :func:`_simpson` by the trapezoidal rule (start and end only), for
    steps far shorter than the currents' time constants (dead times), where the integrands
    are linear to within ``(h/tau)^2``; ``int_W``: ``h^2/6 (2 T_e(0) + T_e(h))``."""
    hh = 0.5 * h
    return (
        h * int_Te + h * (0.5 * h3) * (2.0 * Te + Te_e),
        hh * (Te + Te_e),
        hh * (va * (isa + esa) + vb * (isb + esb)),
        hh * (isa * isa + isb * isb + esa * esa + esb * esb),
        hh * (ira * ira + irb * irb + era * era + erb * erb),
    )


@njit(cache=True)
def switching_period(
    pinv, sinv, pp, x, v_alpha, v_beta, Vdc_meas, R1b, R2b, TL0, Ts, nsub, work, ev, trace
):
    """:func:`bridge_period` with nothing carried from a previous period (``work`` is
    unused, kept for the call signature)."""
    carry = np.zeros(1, dtype=CARRY)
    v = bridge_period(
        pinv, sinv, pp, x, v_alpha, v_beta, Vdc_meas, R1b, R2b, TL0, Ts, nsub, ev, trace,
        carry[0],
    )  # fmt: skip
    carry[0].sat_valid = 0.0  # the array stays alive while its record is in use
    return v


@njit(cache=True)
def bridge_period(pinv, sinv, pp, x, v_alpha, v_beta, Vdc_meas, R1b, R2b, TL0, Ts, nsub, ev,
                  trace, carry, advance=0.0):  # fmt: skip
    """Integrate the plant over one carrier period of the switching bridge (updates ``x``).

    The gate commands of the period (:func:`imdrive.kernels.inverter.gate_commands`) and the
    dead-time transitions they cause are events in time order; between two events the pole
    states are constant and the plant is integrated over that exact interval (module
    docstring: held speed and resistances, Taylor series of the flux equations, Simpson's rule
    for the rest). The phase current at a command instant (from the integrated state) decides
    its dead-time transition. Returns the period-average voltage applied at the terminals, V.

    ``nsub`` splits every interval longer than ``Ts/(40 nsub)`` into ``nsub`` steps. ``carry``
    is a record with :data:`CARRY_FIELDS` (saturated: the curve's series about the period's
    start if the last period left it, and this period's for the next, with the end state's
    stator current). ``ev`` is float64[3, MAX_EVENTS] scratch (times,
    legs, states). ``trace``, float64[n, 3], receives ``(t, i_alpha, i_beta)`` at the start
    of every interval while it has rows (pass a zero-row array for none): the current ripple's
    extremes are at these instants. ``advance``: the modulator's advance of the gate commands,
    s (:func:`imdrive.kernels.inverter.gate_commands`).
    """
    d = duty_cycles(v_alpha, v_beta, Vdc_meas)
    ev_t, ev_leg, ev_state = ev[0], ev[1], ev[2]
    n = gate_commands(sinv, d, Ts, ev_t, ev_leg, ev_state, advance)

    # --- held over the period: resistances, speed; the state at the start
    R1, R2 = winding_resistances(pp, x, R1b, R2b)
    sat = pp.saturation
    sa = x.psi_s_ab.real
    sb = x.psi_s_ab.imag
    ra = x.psi_r_ab.real
    rb = x.psi_r_ab.imag
    g1, g2, k, k_u, k_uu2, u0, xa, xb, co = _period_coefficients(pp, R1, R2, sa, sb, ra, rb, carry)
    c_ss, c_sr, c_rr = co[9], co[10], co[11]
    isa, isb, ira, irb = _currents(c_ss, c_sr, c_rr, sa, sb, ra, rb)
    n_p = pp.n_p
    Tk = 1.5 * n_p
    Te = Tk * (sa * isb - sb * isa)
    w0 = x.w_m
    dw0 = 0.0
    if not pp.speed_imposed:
        dw0 = (Te - load_torque(pp, TL0, w0) - pp.B * w0) / pp.J
    w_r1 = n_p * dw0  # the electrical speed, linear over the period from its start's slope
    a_ss, a_sr, a_rs, a_rr = -R1 * c_ss, -R1 * c_sr, -R2 * c_sr, -R2 * c_rr
    k_end = k  # k at the last step's end (saturated)

    # integrals over the period (Simpson per interval, the trapezoid on short ones); int_W =
    # int_0^Ts int_0^t T_e ds dt, for the held speed's correction; acc_* the volt-seconds
    int_Te = int_W = int_is2 = int_ir2 = e_in = acc_alpha = acc_beta = 0.0
    short = Ts / (40.0 * nsub)  # intervals up to this long: one second-order step
    t = 0.0
    j = 0
    n_tr = 0
    while True:
        t_next, kind, leg = _next_event(sinv, ev_t, ev_leg, j, n, Ts)
        if t_next > t:
            n_tr = _trace(trace, n_tr, t, isa, isb)
            va, vb = pole_voltages_ab(pinv, sinv, pinv.Vdc, isa, isb)
            dt = t_next - t
            n_step, order = (nsub, LONG_ORDER) if dt > short else (1, 2)
            h = dt if n_step == 1 else dt / n_step  # no division in the common case
            h3 = h * THIRD
            for i_step in range(n_step):
                w_r = n_p * w0 + w_r1 * (t + i_step * h)
                if sat and order == 2:  # a short step: k held at its start's value
                    a_ss, a_sr, a_rs, a_rr = _rates_held(k_end, co)
                elif sat:  # k held at its value predicted for the step's middle, from the
                    # start's rates (v - R1 i_s, -R2 i_r + j w_r psi_r) of psi_x
                    hh = 0.5 * h
                    pxa = xa + hh * (g1 * (va - R1 * isa) - g2 * (R2 * ira + w_r * rb))
                    pxb = xb + hh * (g1 * (vb - R1 * isb) + g2 * (w_r * ra - R2 * irb))
                    du = pxa * pxa + pxb * pxb - u0
                    k_mid = k + du * (k_u + k_uu2 * du)
                    a_ss, a_sr, a_rs, a_rr = _rates_held(k_mid, co)
                    c_ss, c_sr, c_rr = _currents_held(k_mid, g1, g2, co)
                d1 = flux_rates(sa, sb, ra, rb, va, vb, a_ss, a_sr, a_rs, a_rr, w_r)
                y = flux_taylor(sa, sb, ra, rb, d1, a_ss, a_sr, a_rs, a_rr, w_r, w_r1, h, order)
                if order > 2:  # the middle (long steps): currents with the held coefficients
                    msa, msb, mra, mrb = _currents(c_ss, c_sr, c_rr, y[0], y[1], y[2], y[3])
                sa, sb, ra, rb = y[4], y[5], y[6], y[7]
                if sat:  # the end's currents: k of the curve at the end's |psi_x| (the rates
                    # keep k of the middle: off the fluxes' chain from step to step)
                    xa = sa * g1 + ra * g2
                    xb = sb * g1 + rb * g2
                    du = xa * xa + xb * xb - u0
                    k_end = k + du * (k_u + k_uu2 * du)
                    c_ss, c_sr, c_rr = _currents_held(k_end, g1, g2, co)
                esa, esb, era, erb = _currents(c_ss, c_sr, c_rr, sa, sb, ra, rb)
                Te_e = Tk * (sa * esb - sb * esa)
                if order > 2:
                    Te_m = Tk * (y[0] * msb - y[1] * msa)
                    dW, dTe, de, ds2, dr2 = _simpson(h, h3, int_Te, va, vb, Te, Te_m, Te_e,
                                                     isa, isb, ira, irb, msa, msb, mra, mrb,
                                                     esa, esb, era, erb)  # fmt: skip
                else:
                    dW, dTe, de, ds2, dr2 = _trapezoid(h, h3, int_Te, va, vb, Te, Te_e, isa, isb,
                                                       ira, irb, esa, esb, era, erb)  # fmt: skip
                int_W += dW
                int_Te += dTe
                e_in += de
                int_is2 += ds2
                int_ir2 += dr2
                isa, isb, ira, irb, Te = esa, esb, era, erb, Te_e
            acc_alpha += dt * va
            acc_beta += dt * vb
            t = t_next
        if kind == 0:
            break
        j = _apply_event(pinv, sinv, kind, leg, ev_state, j, isa, isb, t)
    for q in range(3):  # a dead time running past the period ends in the next one
        if sinv.pend_t[q] >= 0.0:
            sinv.pend_t[q] -= Ts

    # --- the rest of the state, from the period's integrals
    _close_period(pp, x, TL0, Ts, R1, R2, w0, dw0, sa, sb, ra, rb, int_Te, int_W, int_is2,
                  int_ir2, e_in)  # fmt: skip
    if sat:
        _carry(pp, x, carry)
    inv_Ts = 1.0 / Ts
    return acc_alpha * inv_Ts, acc_beta * inv_Ts
