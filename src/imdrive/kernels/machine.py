"""Induction machine: the continuous plant model (compiled).

State variables (stationary alpha-beta frame, amplitude-invariant Clarke, see :mod:`imdrive`):
stator and rotor flux linkages ``psi_s_ab``, ``psi_r_ab`` (Wb), mechanical speed ``w_m`` (rad/s),
mechanical angle, two winding temperatures and four energy accumulators. With flux linkages as
states the electrical equations are::

    d psi_s/dt = v_s - R1 i_s
    d psi_r/dt = -R2 i_r + j w_r psi_r                     (rotor short-circuited)
    [psi_s; psi_r] = [[L1, M], [M, L2]] [i_s; i_r],  L1 = Ll1 + M,  L2 = Ll2 + M
    T_e = 1.5 n_p (psi_s x i_s)
    J dw_m/dt = T_e - T_L(t, w_m) - B w_m

Main-flux saturation (``p.saturation``): the magnetising flux ``psi_m = psi_s - Ll1 i_s =
psi_r - Ll2 i_r`` and current ``i_m = i_s + i_r`` follow the magnetising curve::

    i_m = (psi_m / Lm0) (1 + (|psi_m| / psi_sat)^S),  i.e.  Lm = Lm0 / (1 + (|psi_m|/psi_sat)^S)

a power-law curve, monotone for S > 0 (see :func:`magnetising_current`). Given the states,
``psi_m`` is parallel to ``psi_s/Ll1 + psi_r/Ll2`` and its magnitude solves a scalar monotone
equation, solved from a table of the inverse curve built once per run plus one Newton
correction (:func:`magnetising_ratio`, :func:`saturation_table`; Newton's method to
convergence outside the table). With ``p.saturation`` off the linear T-circuit with ``M`` is
used.

Winding temperatures follow a first-order thermal model per winding::

    tau dtheta/dt = R_th P_cu - (theta - theta_amb),   R = R_ref (1 + alpha (theta - theta_ref))

The flux linkages are the electrical states: the equations are then linear in the state for a
given speed, resistances enter only as coefficients (so R1, R2 may jump without discontinuity
of the state), and the magnetic energy is a function of state.

Each control period the engine integrates the plant over the inverter's voltage segments with
classical RK4 (:func:`integrate_segment`); the switching bridge integrates the flux equations
alone between its edges (:func:`flux_taylor`, see :mod:`imdrive.kernels.bridge`).
RK4 rather than an exact discretisation: the plant is
nonlinear (speed multiplies flux, the thermal model makes R depend on state); the fastest
electrical mode has ``|lambda| ~ 400 1/s`` so ``|lambda| h ~ 0.04`` at the default 100 us, where
RK4's local error is ~1e-9 relative; tests/kernels/test_machine_physics.py measures it against
scipy's solve_ivp.
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.kernels.jit import njit
from imdrive.kernels.records import b1, c16, f8, record_dtype
from imdrive.kernels.saturation import (  # noqa: F401  (re-exported: the model's import path)
    SAT_CELLS,
    SAT_TABLE_TOL,
    magnetising_current,
    magnetising_energy,
    magnetising_ratio,
    magnetising_ratio_series,
    saturated_currents,
    saturation_table,
)

THIRD = 1.0 / 3.0  # the Taylor steps multiply by it: a division costs ~13 cycles per step

#: Parameters of the true machine and its load (SI; temperatures in degC).
PLANT_PARAMS = record_dtype(
    [
        ("R1", f8),  # stator resistance at the reference temperature, ohm
        ("R2", f8),  # rotor resistance (stator-referred) at the reference temperature, ohm
        ("Ll1", f8),  # stator leakage inductance, H
        ("Ll2", f8),  # rotor leakage inductance, H
        ("M", f8),  # magnetising inductance, H
        ("n_p", f8),  # pole pairs
        ("J", f8),  # inertia, kg m^2
        ("B", f8),  # viscous friction of the machine, N m s/rad
        ("k_visc", f8),  # load torque coefficient on w_m, N m s/rad
        ("k_fan", f8),  # load torque coefficient on w_m |w_m|, N m s^2/rad^2
        ("alpha1", f8),  # temperature coefficient of R1, 1/K
        ("alpha2", f8),  # temperature coefficient of R2, 1/K
        ("theta_ref", f8),  # reference temperature of R1, R2, degC
        ("theta_amb", f8),  # ambient temperature, degC
        ("Rth1", f8),  # stator thermal resistance, K/W
        ("tau1", f8),  # stator thermal time constant, s
        ("Rth2", f8),  # rotor thermal resistance, K/W
        ("tau2", f8),  # rotor thermal time constant, s
        ("thermal", b1),  # thermal model on
        ("speed_imposed", b1),  # w_m follows a profile instead of J dw/dt = Te - TL
        ("saturation", b1),  # main-flux saturation on (else the linear M above)
        ("Lm0", f8),  # unsaturated magnetising inductance of the curve, H
        ("psi_sat", f8),  # saturation flux of the curve, Wb
        ("S", f8),  # exponent of the curve
        # table of the inverse magnetising curve (see saturation_table; sat_X_max = 0: none)
        ("sat_X_max", f8),  # end of the table in |psi_x|, A
        ("sat_inv_h", f8),  # 1 / cell width, 1/A
        ("sat_G", f8),  # 1/Ll1 + 1/Ll2, 1/H
        ("sat_inv_Lm0", f8),  # 1/Lm0, 1/H
        ("sat_inv_psi_sat", f8),  # 1/psi_sat, 1/Wb
        ("sat_k", f8, (SAT_CELLS + 1,)),  # k = |psi_m| / |psi_x| at the nodes, H
        ("sat_dk", f8, (SAT_CELLS + 1,)),  # h dk/d|psi_x| at the nodes, H
    ]
)

#: Continuous plant state; ``PLANT_STATE`` has the memory layout of 12 float64.
PLANT_STATE = record_dtype(
    [
        ("psi_s_ab", c16),  # stator flux linkage, Wb
        ("psi_r_ab", c16),  # rotor flux linkage (stator-referred), Wb
        ("w_m", f8),  # mechanical speed, rad/s
        ("theta_m", f8),  # mechanical angle, rad
        ("theta1", f8),  # stator winding temperature, degC
        ("theta2", f8),  # rotor winding temperature, degC
        ("E_in", f8),  # electrical input energy, J
        ("E_cu", f8),  # copper losses, J
        ("E_em", f8),  # air-gap (electromechanical) work, integral of Te w_m, J
        ("E_load", f8),  # work done on the load and friction, J
    ]
)

#: Log fields this block writes (SI units; the result's units table names the columns).
LOG_FIELDS = (
    "speed",  # w_m, rad/s
    "torque",  # T_e, N m
    "load_torque",  # T_L, N m
    "i_alpha",  # plant stator current, A
    "i_beta",
    "psi_r_alpha",  # plant rotor flux, Wb
    "psi_r_beta",
    "R1",  # actual resistances, ohm
    "R2",
    "flux",  # |psi_r|, Wb
    "theta1",  # winding temperatures, degC
    "theta2",
)


@njit(cache=True, inline="always")
def currents_from_fluxes(psi_s_alpha, psi_s_beta, psi_r_alpha, psi_r_beta, L1, L2, M):
    """Stator and rotor currents from the flux linkages, A.

    Inverts ``[psi_s; psi_r] = [[L1, M], [M, L2]] [i_s; i_r]``.
    """
    inv_d = 1.0 / (L1 * L2 - M * M)
    i_s_alpha = (L2 * psi_s_alpha - M * psi_r_alpha) * inv_d
    i_s_beta = (L2 * psi_s_beta - M * psi_r_beta) * inv_d
    i_r_alpha = (L1 * psi_r_alpha - M * psi_s_alpha) * inv_d
    i_r_beta = (L1 * psi_r_beta - M * psi_s_beta) * inv_d
    return i_s_alpha, i_s_beta, i_r_alpha, i_r_beta


@njit(cache=True, inline="always")
def plant_currents(p, psi_s_alpha, psi_s_beta, psi_r_alpha, psi_r_beta):
    """Stator and rotor currents of the plant (linear or saturated), A."""
    i_s_alpha, i_s_beta, i_r_alpha, i_r_beta, _ = plant_currents_m(
        p, psi_s_alpha, psi_s_beta, psi_r_alpha, psi_r_beta, -1.0
    )
    return i_s_alpha, i_s_beta, i_r_alpha, i_r_beta


@njit(cache=True, inline="always")
def plant_currents_m(p, psi_s_alpha, psi_s_beta, psi_r_alpha, psi_r_beta, m0):
    """:func:`plant_currents` and ``|psi_m|`` (0 when linear), from a start ``m0`` for the
    saturated solve (``m0 < 0``: the default start)."""
    if p.saturation:
        return saturated_currents(p, psi_s_alpha, psi_s_beta, psi_r_alpha, psi_r_beta, m0)
    L1 = p.Ll1 + p.M
    L2 = p.Ll2 + p.M
    i_s_alpha, i_s_beta, i_r_alpha, i_r_beta = currents_from_fluxes(
        psi_s_alpha, psi_s_beta, psi_r_alpha, psi_r_beta, L1, L2, p.M
    )
    return i_s_alpha, i_s_beta, i_r_alpha, i_r_beta, 0.0


@njit(cache=True, inline="always")
def stator_current_m(p, x, m0):
    """:func:`stator_current` and ``|psi_m|`` from the start ``m0`` of the saturated solve."""
    i_s_alpha, i_s_beta, _, _, m = plant_currents_m(
        p, x.psi_s_ab.real, x.psi_s_ab.imag, x.psi_r_ab.real, x.psi_r_ab.imag, m0
    )
    return i_s_alpha, i_s_beta, m


@njit(cache=True, inline="always")
def stator_current(p, x):
    """Stator current ``(i_s_alpha, i_s_beta)`` of plant state ``x``, A."""
    i_s_alpha, i_s_beta, _, _ = plant_currents(
        p, x.psi_s_ab.real, x.psi_s_ab.imag, x.psi_r_ab.real, x.psi_r_ab.imag
    )
    return i_s_alpha, i_s_beta


@njit(cache=True)
def winding_resistances(p, x, R1_base, R2_base):
    """Actual R1, R2 (ohm): the profile-scaled base values times the thermal factor."""
    if p.thermal:
        R1 = R1_base * (1.0 + p.alpha1 * (x.theta1 - p.theta_ref))
        R2 = R2_base * (1.0 + p.alpha2 * (x.theta2 - p.theta_ref))
        return R1, R2
    return R1_base, R2_base


@njit(cache=True)
def load_torque(p, TL0, w_m):
    """Load torque T_L = T0(t) + b w_m + k_fan w_m |w_m|, N m (positive opposes forward motion)."""
    return TL0 + p.k_visc * w_m + p.k_fan * w_m * abs(w_m)


@njit(cache=True)
def electromagnetic_torque(psi_s_alpha, psi_s_beta, i_s_alpha, i_s_beta, n_p):
    """T_e = 1.5 n_p (psi_s x i_s), N m."""
    return 1.5 * n_p * (psi_s_alpha * i_s_beta - psi_s_beta * i_s_alpha)


@njit(cache=True)
def _rates(p, psa, psb, pra, prb, w_m, th1, th2, v_alpha, v_beta, R1_base, R2_base, TL0, m0=-1.0):
    """The plant's time derivatives from its state variables (the equations of the module
    docstring), as a 12-tuple in the field order of ``PLANT_STATE``.

    Scalars in, scalars out: the RK4 of :func:`integrate_segment` keeps its stages in
    registers instead of records. The 13th element is ``|psi_m|`` of the saturated solve, the
    start ``m0`` of the next stage's.
    """
    n_p = p.n_p
    if p.thermal:
        R1 = R1_base * (1.0 + p.alpha1 * (th1 - p.theta_ref))
        R2 = R2_base * (1.0 + p.alpha2 * (th2 - p.theta_ref))
    else:
        R1 = R1_base
        R2 = R2_base
    i_s_alpha, i_s_beta, i_r_alpha, i_r_beta, m = plant_currents_m(p, psa, psb, pra, prb, m0)
    w_r = n_p * w_m
    T_e = electromagnetic_torque(psa, psb, i_s_alpha, i_s_beta, n_p)
    T_L = load_torque(p, TL0, w_m)
    if not p.speed_imposed:
        dw = (T_e - T_L - p.B * w_m) / p.J
    else:  # speed imposed: the engine writes x.w_m from its profile every period
        dw = 0.0
    p_cu1 = 1.5 * R1 * (i_s_alpha * i_s_alpha + i_s_beta * i_s_beta)
    p_cu2 = 1.5 * R2 * (i_r_alpha * i_r_alpha + i_r_beta * i_r_beta)
    if p.thermal:
        dth1 = (p.Rth1 * p_cu1 - (th1 - p.theta_amb)) / p.tau1
        dth2 = (p.Rth2 * p_cu2 - (th2 - p.theta_amb)) / p.tau2
    else:
        dth1 = 0.0
        dth2 = 0.0
    return (
        v_alpha - R1 * i_s_alpha,
        v_beta - R1 * i_s_beta,
        -R2 * i_r_alpha - w_r * prb,
        -R2 * i_r_beta + w_r * pra,
        dw,
        w_m,
        dth1,
        dth2,
        1.5 * (v_alpha * i_s_alpha + v_beta * i_s_beta),
        p_cu1 + p_cu2,
        T_e * w_m,
        (T_L + p.B * w_m) * w_m,
        m,
    )


@njit(cache=True)
def _store(x, y):
    """Write a 12-tuple in ``PLANT_STATE`` field order into the record ``x``."""
    x.psi_s_ab = complex(y[0], y[1])
    x.psi_r_ab = complex(y[2], y[3])
    x.w_m = y[4]
    x.theta_m = y[5]
    x.theta1 = y[6]
    x.theta2 = y[7]
    x.E_in = y[8]
    x.E_cu = y[9]
    x.E_em = y[10]
    x.E_load = y[11]


@njit(cache=True)
def machine_derivative(p, x, v_alpha, v_beta, R1_base, R2_base, TL0, dx):
    """Time derivative of the plant state (writes the record ``dx``).

    Parameters
    ----------
    p : PLANT_PARAMS record
    x : PLANT_STATE record
    v_alpha, v_beta : float
        Stator voltage space vector applied by the inverter, V.
    R1_base, R2_base : float
        Resistances at the reference temperature, already scaled by their time profiles, ohm.
    TL0 : float
        Time-dependent part of the load torque, N m.
    dx : PLANT_STATE record
        Output.
    """
    d = _rates(
        p,
        x.psi_s_ab.real,
        x.psi_s_ab.imag,
        x.psi_r_ab.real,
        x.psi_r_ab.imag,
        x.w_m,
        x.theta1,
        x.theta2,
        v_alpha,
        v_beta,
        R1_base,
        R2_base,
        TL0,
    )
    _store(dx, d)


@njit(cache=True)
def _axpy12(y, a, k):
    """``y + a k`` for 12-tuples (an RK4 stage)."""
    return (
        y[0] + a * k[0],
        y[1] + a * k[1],
        y[2] + a * k[2],
        y[3] + a * k[3],
        y[4] + a * k[4],
        y[5] + a * k[5],
        y[6] + a * k[6],
        y[7] + a * k[7],
        y[8] + a * k[8],
        y[9] + a * k[9],
        y[10] + a * k[10],
        y[11] + a * k[11],
    )


@njit(cache=True)
def _rk4_sum(x0, x1, x2, x3, h6):
    """The RK4 combination ``h/6 (k1 + 2 k2 + 2 k3 + k4)`` of one component."""
    return h6 * (x0 + 2.0 * x1 + 2.0 * x2 + x3)


@njit(cache=True)
def integrate_segment(p, x, v_alpha, v_beta, R1b, R2b, TL0, dt, nsub, work, m0=-1.0):
    """Integrate the plant over ``dt`` with ``nsub`` RK4 steps at constant voltage (in place).

    The stages live in local 12-tuples (registers), the state record is read once and written
    once. ``work`` is unused scratch kept for the call signature. ``m0`` starts the saturated
    solve of the first stage (``< 0``: the default start); returns the last stage's
    ``|psi_m|``, a start for the next call.
    """
    h = dt / nsub
    y = (
        x.psi_s_ab.real,
        x.psi_s_ab.imag,
        x.psi_r_ab.real,
        x.psi_r_ab.imag,
        x.w_m,
        x.theta_m,
        x.theta1,
        x.theta2,
        x.E_in,
        x.E_cu,
        x.E_em,
        x.E_load,
    )
    m = m0
    for _ in range(nsub):
        k1 = _rates(p, y[0], y[1], y[2], y[3], y[4], y[6], y[7], v_alpha, v_beta, R1b, R2b, TL0, m)
        yt = _axpy12(y, 0.5 * h, k1)
        m = k1[12]
        k2 = _rates(
            p, yt[0], yt[1], yt[2], yt[3], yt[4], yt[6], yt[7], v_alpha, v_beta, R1b, R2b, TL0, m
        )
        yt = _axpy12(y, 0.5 * h, k2)
        k3 = _rates(
            p, yt[0], yt[1], yt[2], yt[3], yt[4], yt[6], yt[7], v_alpha, v_beta, R1b, R2b, TL0, m
        )
        yt = _axpy12(y, h, k3)
        k4 = _rates(
            p, yt[0], yt[1], yt[2], yt[3], yt[4], yt[6], yt[7], v_alpha, v_beta, R1b, R2b, TL0, m
        )
        m = k4[12]
        h6 = h / 6.0
        y = (
            y[0] + _rk4_sum(k1[0], k2[0], k3[0], k4[0], h6),
            y[1] + _rk4_sum(k1[1], k2[1], k3[1], k4[1], h6),
            y[2] + _rk4_sum(k1[2], k2[2], k3[2], k4[2], h6),
            y[3] + _rk4_sum(k1[3], k2[3], k3[3], k4[3], h6),
            y[4] + _rk4_sum(k1[4], k2[4], k3[4], k4[4], h6),
            y[5] + _rk4_sum(k1[5], k2[5], k3[5], k4[5], h6),
            y[6] + _rk4_sum(k1[6], k2[6], k3[6], k4[6], h6),
            y[7] + _rk4_sum(k1[7], k2[7], k3[7], k4[7], h6),
            y[8] + _rk4_sum(k1[8], k2[8], k3[8], k4[8], h6),
            y[9] + _rk4_sum(k1[9], k2[9], k3[9], k4[9], h6),
            y[10] + _rk4_sum(k1[10], k2[10], k3[10], k4[10], h6),
            y[11] + _rk4_sum(k1[11], k2[11], k3[11], k4[11], h6),
        )
    _store(x, y)
    return m


@njit(cache=True)
def integrate_short(p, x, v_alpha, v_beta, R1b, R2b, TL0, dt, m0=-1.0):
    """One midpoint (RK2) step over a short interval (a dead time, a narrow pulse; in place).

    Its local error, ``~(lambda dt)^3/6`` with ``|lambda| ~ 500 1/s`` the fastest electrical
    mode, is below RK4's over a whole period for ``dt <= Ts/40`` (2.5 us at 10 kHz), at half
    the cost; ``tests/drive/test_realistic_drive.py`` measures the switching model against
    solve_ivp.
    """
    y0 = x.psi_s_ab.real
    y1 = x.psi_s_ab.imag
    y2 = x.psi_r_ab.real
    y3 = x.psi_r_ab.imag
    k1 = _rates(p, y0, y1, y2, y3, x.w_m, x.theta1, x.theta2, v_alpha, v_beta, R1b, R2b, TL0, m0)
    a = 0.5 * dt
    k2 = _rates(
        p,
        y0 + a * k1[0],
        y1 + a * k1[1],
        y2 + a * k1[2],
        y3 + a * k1[3],
        x.w_m + a * k1[4],
        x.theta1 + a * k1[6],
        x.theta2 + a * k1[7],
        v_alpha,
        v_beta,
        R1b,
        R2b,
        TL0,
        k1[12],
    )
    x.psi_s_ab = complex(y0 + dt * k2[0], y1 + dt * k2[1])
    x.psi_r_ab = complex(y2 + dt * k2[2], y3 + dt * k2[3])
    x.w_m += dt * k2[4]
    x.theta_m += dt * k2[5]
    x.theta1 += dt * k2[6]
    x.theta2 += dt * k2[7]
    x.E_in += dt * k2[8]
    x.E_cu += dt * k2[9]
    x.E_em += dt * k2[10]
    x.E_load += dt * k2[11]
    return k2[12]


@njit(cache=True)
def current_coefficients(p, k):
    """``(c_ss, c_sr, c_rr)`` of ``i_s = c_ss psi_s + c_sr psi_r``, ``i_r = c_sr psi_s + c_rr
    psi_r``, 1/H.

    Linear machine: the inverse of ``[[L1, M], [M, L2]]``. Saturated, with the magnetising
    ratio ``k = |psi_m|/|psi_x|`` held (:func:`magnetising_ratio`): ``psi_m = k psi_x`` makes
    the currents ``(psi_s - psi_m)/Ll1``, ``(psi_r - psi_m)/Ll2`` linear in the fluxes.
    """
    if p.saturation:
        g1 = 1.0 / p.Ll1
        g2 = 1.0 / p.Ll2
        return (1.0 - k * g1) * g1, -k * g1 * g2, (1.0 - k * g2) * g2
    L1 = p.Ll1 + p.M
    L2 = p.Ll2 + p.M
    inv_d = 1.0 / (L1 * L2 - p.M * p.M)
    return L2 * inv_d, -p.M * inv_d, L1 * inv_d


@njit(cache=True, inline="always")
def flux_rates(sa, sb, ra, rb, va, vb, a_ss, a_sr, a_rs, a_rr, w_r):
    """``d/dt (psi_s, psi_r)`` of the electrical equations with held coefficients, Wb/s.

    ``d psi_s/dt = v + a_ss psi_s + a_sr psi_r``, ``d psi_r/dt = a_rs psi_s + a_rr psi_r +
    j w_r psi_r`` with ``a_ss = -R1 c_ss``, ``a_sr = -R1 c_sr``, ``a_rs = -R2 c_sr``,
    ``a_rr = -R2 c_rr`` (:func:`current_coefficients`).
    """
    return (
        va + a_ss * sa + a_sr * ra,
        vb + a_ss * sb + a_sr * rb,
        a_rs * sa + a_rr * ra - w_r * rb,
        a_rs * sb + a_rr * rb + w_r * ra,
    )


@njit(cache=True, inline="always")
def flux_taylor(sa, sb, ra, rb, d1, a_ss, a_sr, a_rs, a_rr, w_r, w_r1, h, order):
    """Fluxes at ``h/2`` and ``h`` of the held-coefficient electrical system (8-tuple).

    The system ``dy/dt = A(t) y + b`` (:func:`flux_rates`; the voltage ``b`` constant over
    the interval) with the speed linear in time, ``A(t) = A + t A1`` (``A1 y = j w_r1 psi_r``,
    ``w_r1`` the electrical speed's rate of change, rad/s^2), has the derivatives
    ``d2 = A d1 + A1 y``, ``d3 = A d2 + 2 A1 d1``, ``d4 = A d3 + 3 A1 d2`` (``dn`` the n-th
    derivative at the interval's start, ``d1`` given), so its Taylor series
    ``y(tau) = y + tau d1 + tau^2/2 d2 + ...`` is exact up to ``order`` (2, 3 or 4). Order 4 is
    the classical RK4 of a linear system (local error ``(|lambda| h)^5/120``), order 3 leaves
    ``(|lambda| h)^4/24``; order 2 serves intervals far shorter than the fastest time constant
    (dead times).

    The higher derivatives have no voltage: it is passed as ``-0.0``, which the compiler
    drops from the sums (``-0.0 + x`` is ``x`` exactly; ``0.0 + x`` is not for ``x = -0.0``,
    so it would stay an addition on the chain from one derivative to the next).
    """
    d2 = flux_rates(d1[0], d1[1], d1[2], d1[3], -0.0, -0.0, a_ss, a_sr, a_rs, a_rr, w_r)
    d2 = (d2[0], d2[1], d2[2] - w_r1 * rb, d2[3] + w_r1 * ra)
    q = 0.5 * h
    if order >= 3:
        d3 = flux_rates(d2[0], d2[1], d2[2], d2[3], -0.0, -0.0, a_ss, a_sr, a_rs, a_rr, w_r)
        d3 = (d3[0], d3[1], d3[2] - 2.0 * w_r1 * d1[3], d3[3] + 2.0 * w_r1 * d1[2])
        m3 = e3 = d3  # the innermost Horner terms, for the middle and the end
        if order >= 4:
            d4 = flux_rates(d3[0], d3[1], d3[2], d3[3], -0.0, -0.0, a_ss, a_sr, a_rs, a_rr, w_r)
            d4 = (d4[0], d4[1], d4[2] - 3.0 * w_r1 * d2[3], d4[3] + 3.0 * w_r1 * d2[2])
            c4 = 0.25 * q
            m3 = (d3[0] + c4 * d4[0], d3[1] + c4 * d4[1], d3[2] + c4 * d4[2], d3[3] + c4 * d4[3])
            c4 = 0.25 * h
            e3 = (d3[0] + c4 * d4[0], d3[1] + c4 * d4[1], d3[2] + c4 * d4[2], d3[3] + c4 * d4[3])
        h3 = h * THIRD  # a multiply: h/3 to within one rounding
        c2 = 0.5 * q
        c3 = 0.5 * h3  # q/3, exactly
        m0 = sa + q * (d1[0] + c2 * (d2[0] + c3 * m3[0]))
        m1 = sb + q * (d1[1] + c2 * (d2[1] + c3 * m3[1]))
        m2 = ra + q * (d1[2] + c2 * (d2[2] + c3 * m3[2]))
        m3_ = rb + q * (d1[3] + c2 * (d2[3] + c3 * m3[3]))
        c2 = 0.5 * h
        e0 = sa + h * (d1[0] + c2 * (d2[0] + h3 * e3[0]))
        e1 = sb + h * (d1[1] + c2 * (d2[1] + h3 * e3[1]))
        e2 = ra + h * (d1[2] + c2 * (d2[2] + h3 * e3[2]))
        e3_ = rb + h * (d1[3] + c2 * (d2[3] + h3 * e3[3]))
        return m0, m1, m2, m3_, e0, e1, e2, e3_
    c2 = 0.5 * q
    m0 = sa + q * (d1[0] + c2 * d2[0])
    m1 = sb + q * (d1[1] + c2 * d2[1])
    m2 = ra + q * (d1[2] + c2 * d2[2])
    m3 = rb + q * (d1[3] + c2 * d2[3])
    c2 = 0.5 * h
    e0 = sa + h * (d1[0] + c2 * d2[0])
    e1 = sb + h * (d1[1] + c2 * d2[1])
    e2 = ra + h * (d1[2] + c2 * d2[2])
    e3 = rb + h * (d1[3] + c2 * d2[3])
    return m0, m1, m2, m3, e0, e1, e2, e3


@njit(cache=True)
def magnetic_energy(p, x):
    """Energy stored in the magnetic field, J.

    Linear: ``1.5 * 0.5 * (psi_s.i_s + psi_r.i_r)``. Saturated: the leakage energies
    ``1.5 * 0.5 (Ll1 |i_s|^2 + Ll2 |i_r|^2)`` plus ``1.5 int i_m dpsi_m`` along the curve.
    """
    psi_s_alpha = x.psi_s_ab.real
    psi_s_beta = x.psi_s_ab.imag
    psi_r_alpha = x.psi_r_ab.real
    psi_r_beta = x.psi_r_ab.imag
    if p.saturation:
        i_s_alpha, i_s_beta, i_r_alpha, i_r_beta, m = saturated_currents(
            p, psi_s_alpha, psi_s_beta, psi_r_alpha, psi_r_beta
        )
        leak = p.Ll1 * (i_s_alpha**2 + i_s_beta**2) + p.Ll2 * (i_r_alpha**2 + i_r_beta**2)
        return 0.75 * leak + 1.5 * magnetising_energy(m, p.Lm0, p.psi_sat, p.S)
    L1 = p.Ll1 + p.M
    L2 = p.Ll2 + p.M
    i_s_alpha, i_s_beta, i_r_alpha, i_r_beta = currents_from_fluxes(
        psi_s_alpha, psi_s_beta, psi_r_alpha, psi_r_beta, L1, L2, p.M
    )
    return 0.75 * (
        psi_s_alpha * i_s_alpha
        + psi_s_beta * i_s_beta
        + psi_r_alpha * i_r_alpha
        + psi_r_beta * i_r_beta
    )


@njit(cache=True)
def log_plant(row, p, x, i_s_alpha, i_s_beta, TL0, R1b, R2b):
    """Write this block's :data:`LOG_FIELDS` of the sample into the log record ``row``."""
    R1, R2 = winding_resistances(p, x, R1b, R2b)
    row.speed = x.w_m
    row.torque = electromagnetic_torque(
        x.psi_s_ab.real, x.psi_s_ab.imag, i_s_alpha, i_s_beta, p.n_p
    )
    row.load_torque = load_torque(p, TL0, x.w_m)
    row.i_alpha = i_s_alpha
    row.i_beta = i_s_beta
    row.psi_r_alpha = x.psi_r_ab.real
    row.psi_r_beta = x.psi_r_ab.imag
    row.R1 = R1
    row.R2 = R2
    row.flux = math.sqrt(x.psi_r_ab.real**2 + x.psi_r_ab.imag**2)
    row.theta1 = x.theta1
    row.theta2 = x.theta2


def initial_plant_state(theta_init_C: float = 20.0, w_m0: float = 0.0) -> np.ndarray:
    """Plant state at rest (or at ``w_m0``), demagnetised, windings at ``theta_init_C``."""
    x = np.zeros(1, dtype=PLANT_STATE)
    x["w_m"] = w_m0
    x["theta1"] = theta_init_C
    x["theta2"] = theta_init_C
    return x
