"""Schauder's MRAS speed estimator (paper §2, eqs. 1, 2, 4, 8, 9).

Reference model (voltage model, eq. 1), stationary frame, no speed in it::

    p lam = (L2/M) (v - R1 i - sigma L1 p i)

Adjustable model (current model, eq. 2)::

    p lam_hat = (-1/T2_hat + j w_r_hat) lam_hat + (M/T2_hat) i,    T2_hat = L2/R2_hat

Schauder replaces the reference model's pure integrator ``1/s`` by ``1/(s + wc)`` and passes the
adjustable model's derivative through the same filter, so the two outputs stay comparable; with
``wc = 0`` both are pure integrators. Adaptation (eqs. 4, 8, 9)::

    e = lam_q lam_hat_d - lam_d lam_hat_q,    w_r_hat = K1 e + K2 \\int e dt

(d, q here are the stationary axes alpha, beta).

Discretisation at the control period Ts, with the voltage applied over the last period known
exactly (it was held) and the current taken as the mean of its two end samples:

* reference model increment ``(L2/M) [Ts (v - R1 i_mean) - sigma L1 (i_k - i_{k-1})]``; the
  ``p i`` term integrates exactly to a current difference, so no derivative is ever taken;
* adjustable model: exact solution of the linear 2-D system over Ts for constant w_r_hat and a
  current varying linearly between its samples (complex exponentials);
* the common filter ``1/(s + wc)`` of a derivative constant over the period: exact.
"""

from __future__ import annotations

import math

from numba import njit

from imdrive.kernels.layout import (
    C_E_D0,
    C_E_Q0,
    C_I_PREV_A,
    C_I_PREV_B,
    C_INT_E,
    C_LAM_F_A,
    C_LAM_F_B,
    C_LAM_I_A,
    C_LAM_I_B,
    C_LAM_V_A,
    C_LAM_V_B,
    C_R2_HAT,
    C_THETA_E,
    C_V_PREV_A,
    C_V_PREV_B,
    C_W_HAT,
    P_K1,
    P_K2,
    P_LL1_HAT,
    P_LL2_HAT,
    P_M_HAT,
    P_R1_HAT,
    P_WC,
)


@njit(cache=True)
def mras_step(par, c, i_a, i_b, Ts):
    """Advance the MRAS by one control period to the new current sample (updates ``c``).

    Parameters
    ----------
    par : float64[N_PAR]
        Uses the controller's machine model ``P_*_HAT``, ``P_WC``, ``P_K1``, ``P_K2``.
    c : float64[NC]
        Controller state. Reads the last voltage ``C_V_PREV_*`` and current ``C_I_PREV_*``, the
        estimate ``C_R2_HAT`` and the field angle ``C_THETA_E``; writes the model fluxes, the
        speed estimate ``C_W_HAT`` (electrical rad/s) and ``C_E_D0``, ``C_E_Q0``.
    i_a, i_b : float
        Measured stator current at this sample, A.
    Ts : float
        Control period, s.
    """
    M = par[P_M_HAT]
    L1 = par[P_LL1_HAT] + M
    L2 = par[P_LL2_HAT] + M
    sigma_L1 = L1 - M * M / L2
    R1 = par[P_R1_HAT]
    R2 = c[C_R2_HAT]
    wc = par[P_WC]

    # the common filter 1/(s + wc) applied to a derivative held over the period
    if wc > 0.0:
        g = math.exp(-wc * Ts)
        k_in = (1.0 - g) / (wc * Ts)
    else:
        g = 1.0
        k_in = 1.0

    i_mean_a = 0.5 * (i_a + c[C_I_PREV_A])
    i_mean_b = 0.5 * (i_b + c[C_I_PREV_B])

    # reference (voltage) model, eq. (1)
    kv = L2 / M
    d_a = kv * (Ts * (c[C_V_PREV_A] - R1 * i_mean_a) - sigma_L1 * (i_a - c[C_I_PREV_A]))
    d_b = kv * (Ts * (c[C_V_PREV_B] - R1 * i_mean_b) - sigma_L1 * (i_b - c[C_I_PREV_B]))
    lam_v_a = g * c[C_LAM_V_A] + k_in * d_a
    lam_v_b = g * c[C_LAM_V_B] + k_in * d_b

    # adjustable (current) model, eq. (2): exact over Ts for constant w_hat and a current
    # varying linearly between its two samples (first-order hold)
    zT = complex(-R2 / L2, c[C_W_HAT]) * Ts
    ez = math.exp(zT.real) * complex(math.cos(zT.imag), math.sin(zT.imag))
    if abs(zT) > 1e-4:
        phi1 = (ez - 1.0) / zT
        phi2 = (ez - 1.0 - zT) / (zT * zT)
    else:  # series, avoids cancellation
        phi1 = 1.0 + zT / 2.0 + zT * zT / 6.0
        phi2 = 0.5 + zT / 6.0 + zT * zT / 24.0
    lam_old = complex(c[C_LAM_I_A], c[C_LAM_I_B])
    b = M * R2 / L2 * Ts
    i0 = complex(c[C_I_PREV_A], c[C_I_PREV_B])
    i1 = complex(i_a, i_b)
    lam_new = ez * lam_old + b * (phi1 * i0 + phi2 * (i1 - i0))
    dlam = lam_new - lam_old
    lam_f_a = g * c[C_LAM_F_A] + k_in * dlam.real
    lam_f_b = g * c[C_LAM_F_B] + k_in * dlam.imag

    # adaptation, eqs. (4), (8), (9)
    e = lam_v_b * lam_f_a - lam_v_a * lam_f_b
    c[C_INT_E] += Ts * e
    c[C_W_HAT] = par[P_K1] * e + par[P_K2] * c[C_INT_E]

    # flux error (reference minus adjustable) in the controller's synchronous frame
    th = c[C_THETA_E]
    cs = math.cos(th)
    sn = math.sin(th)
    err_a = lam_v_a - lam_f_a
    err_b = lam_v_b - lam_f_b
    c[C_E_D0] = cs * err_a + sn * err_b
    c[C_E_Q0] = -sn * err_a + cs * err_b

    c[C_LAM_V_A] = lam_v_a
    c[C_LAM_V_B] = lam_v_b
    c[C_LAM_I_A] = lam_new.real
    c[C_LAM_I_B] = lam_new.imag
    c[C_LAM_F_A] = lam_f_a
    c[C_LAM_F_B] = lam_f_b
