"""Indirect field-oriented (vector) control and the open-loop voltage drive.

Indirect field orientation (the paper's Fig. 4): the controller's synchronous frame has the angle

    theta_e = \\int (n_p w_fb + w_sl) dt,     w_sl = (M_hat / T2_hat) iq* / psi_hat,
    T2_hat d(psi_hat)/dt + psi_hat = M_hat id*,  T2_hat = L2_hat / R2_hat

where ``w_fb`` is the speed feedback (measured, or the MRAS estimate) and ``R2_hat`` the
*estimated* rotor resistance, so a wrong R2_hat shows up exactly where it does in a real drive.
In steady state ``psi_hat = M_hat id*`` and the slip is the paper's ``(R2_hat/L2_hat) iq*/id*``;
the flux model keeps the orientation right while the flux changes (magnetising, or the injected
sinusoid of the persistent-excitation compensator).
The rotor-flux reference is expressed as the flux-current reference ``id* = psi* / M_hat`` (plus
an optional injected sinusoid); the speed PI gives a torque command, expressed as the q current
at the reference flux and divided by the flux model, ``iq* = u psi*/psi_hat``, so the torque
does not follow flux changes; synchronous-frame current PIs with
cross-coupling and back-emf feed-forward give the voltage, limited to the inverter's range.

Gain formulas (the defaults; each can be overridden in the scenario):

* current PI, pole-zero cancellation of the stator transient ``sigma L1 di/dt = v - R_sigma i``
  (``R_sigma = R1 + (M/L2)^2 R2``)::

      kp_i = sigma L1 a_c,   ki_i = R_sigma a_c            (closed loop ~ a_c / (s + a_c))

* speed PI, with ``k_t = 1.5 n_p (M/L2) psi*`` the torque constant (N m/A)::

      kp_w = J a_s / k_t,    ki_w = kp_w a_s / 4           (crossover ~ a_s, PI zero at a_s/4)

Both PIs use back-calculation anti-windup: after saturation the integral state is corrected by
the part of the output that could not be applied, so the next output starts from the limit.
"""

from __future__ import annotations

import math

from numba import njit

from imdrive.kernels.inverter import limit_magnitude
from imdrive.kernels.layout import (
    C_I_D,
    C_I_Q,
    C_ID_REF,
    C_INT_D,
    C_INT_Q,
    C_INT_W,
    C_IQ_REF,
    C_PSI_HAT,
    C_R2_HAT,
    C_THETA_E,
    C_THETA_OL,
    C_W_E,
    P_DECOUPLE,
    P_I_MAX,
    P_KI_I,
    P_KI_W,
    P_KP_I,
    P_KP_W,
    P_LL1_HAT,
    P_LL2_HAT,
    P_M_HAT,
    P_NP,
    P_VDC,
)


@njit(cache=True)
def wrap_angle(th):
    """Wrap an angle to [-pi, pi)."""
    return (th + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True)
def open_loop_voltage(c, v_amp, f_Hz, Ts):
    """Balanced sinusoidal voltage for the next period (updates the angle in ``c``).

    The sinusoid is sampled at the middle of the period, so the held voltage has the
    continuous sinusoid's phase (its amplitude is reduced by sinc(w Ts/2), 6e-5 at 60 Hz, 10 kHz).
    """
    w = 2.0 * math.pi * f_Hz
    th = c[C_THETA_OL] + 0.5 * w * Ts
    c[C_THETA_OL] = wrap_angle(c[C_THETA_OL] + w * Ts)
    return v_amp * math.cos(th), v_amp * math.sin(th)


@njit(cache=True)
def foc_step(par, c, i_a, i_b, w_fb_m, w_ref_m, psi_ref, i_inj, Ts):
    """One period of indirect field-oriented speed control (updates ``c``).

    Parameters
    ----------
    par : float64[N_PAR]
    c : float64[NC]
        Controller state; ``C_R2_HAT`` is the rotor-resistance estimate the slip uses.
    i_a, i_b : float
        Measured stator current, stationary frame, A.
    w_fb_m : float
        Speed feedback, mechanical rad/s (measured or estimated).
    w_ref_m : float
        Speed reference, mechanical rad/s.
    psi_ref : float
        Rotor-flux reference, Wb.
    i_inj : float
        Component added to the flux-current reference id* (the injected sinusoid), A.
    Ts : float
        Control period, s.

    Returns
    -------
    v_a, v_b : float
        Voltage reference for the next period, stationary frame, V.
    """
    M = par[P_M_HAT]
    L1 = par[P_LL1_HAT] + M
    L2 = par[P_LL2_HAT] + M
    sigma_L1 = L1 - M * M / L2
    n_p = par[P_NP]
    i_max = par[P_I_MAX]

    # flux-current reference, plus the injected component (persistent excitation)
    id_ref = min(psi_ref / M + i_inj, i_max)

    # the controller's rotor-flux model (exact for id* held over the period)
    T2_hat = L2 / c[C_R2_HAT]
    g = math.exp(-Ts / T2_hat)
    psi_hat = c[C_PSI_HAT]
    # floor: keeps slip and torque current finite while the machine is still unmagnetised
    psi_div = max(psi_hat, 0.05 * M * abs(id_ref), 1e-6)

    # speed PI -> torque command, expressed as the q current at the reference flux; divided by
    # the modelled flux so the torque does not follow flux changes (injection, magnetising)
    iq_max = math.sqrt(max(i_max * i_max - id_ref * id_ref, 0.0))
    err_w = w_ref_m - w_fb_m
    u_unsat = par[P_KP_W] * err_w + c[C_INT_W]
    flux_gain = psi_ref / psi_div
    iq_ref = min(max(u_unsat * flux_gain, -iq_max), iq_max)
    c[C_INT_W] += par[P_KI_W] * Ts * err_w + (iq_ref / flux_gain - u_unsat)

    # synchronous frame: slip from the estimated rotor time constant
    th = c[C_THETA_E]
    cs = math.cos(th)
    sn = math.sin(th)
    i_d = cs * i_a + sn * i_b
    i_q = -sn * i_a + cs * i_b
    w_sl = M * iq_ref / (T2_hat * psi_div)
    c[C_PSI_HAT] = g * psi_hat + (1.0 - g) * M * id_ref
    w_e = n_p * w_fb_m + w_sl

    # current PIs with decoupling; the d axis has priority in the voltage limit (keeps flux)
    kp = par[P_KP_I]
    ki = par[P_KI_I]
    e_d = id_ref - i_d
    e_q = iq_ref - i_q
    ff_d = 0.0
    ff_q = 0.0
    if par[P_DECOUPLE] != 0.0:
        ff_d = -w_e * sigma_L1 * iq_ref
        ff_q = w_e * (sigma_L1 * id_ref + M / L2 * psi_hat)
    v_d_unsat = kp * e_d + c[C_INT_D] + ff_d
    v_q_unsat = kp * e_q + c[C_INT_Q] + ff_q
    v_max = par[P_VDC] / math.sqrt(3.0)
    v_d = min(max(v_d_unsat, -v_max), v_max)
    v_q_max = math.sqrt(max(v_max * v_max - v_d * v_d, 0.0))
    v_q = min(max(v_q_unsat, -v_q_max), v_q_max)
    c[C_INT_D] += ki * Ts * e_d + (v_d - v_d_unsat)
    c[C_INT_Q] += ki * Ts * e_q + (v_q - v_q_unsat)

    # back to the stationary frame at the middle of the period, where the held voltage acts
    th_mid = th + 0.5 * w_e * Ts
    cm = math.cos(th_mid)
    sm = math.sin(th_mid)
    v_a = cm * v_d - sm * v_q
    v_b = sm * v_d + cm * v_q
    v_a, v_b = limit_magnitude(v_a, v_b, v_max)

    c[C_THETA_E] = wrap_angle(th + w_e * Ts)
    c[C_W_E] = w_e
    c[C_ID_REF] = id_ref
    c[C_IQ_REF] = iq_ref
    c[C_I_D] = i_d
    c[C_I_Q] = i_q
    return v_a, v_b
