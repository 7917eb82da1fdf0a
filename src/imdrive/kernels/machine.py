"""Induction machine: parameters (T-equivalent circuit) and the continuous plant model.

State variables (stationary alpha-beta frame, amplitude-invariant Clarke, see :mod:`imdrive`):
stator and rotor flux linkages ``psi_s_ab``, ``psi_r_ab`` (Wb), mechanical speed ``w_m`` (rad/s),
mechanical angle, two winding temperatures and four energy accumulators. With flux linkages as
states the electrical equations are::

    d psi_s/dt = v_s - R1 i_s
    d psi_r/dt = -R2 i_r + j w_r psi_r                     (rotor short-circuited)
    [psi_s; psi_r] = [[L1, M], [M, L2]] [i_s; i_r],  L1 = Ll1 + M,  L2 = Ll2 + M
    T_e = 1.5 n_p (psi_s x i_s)
    J dw_m/dt = T_e - T_L(t, w_m) - B w_m

Winding temperatures follow a first-order thermal model per winding::

    tau dtheta/dt = R_th P_cu - (theta - theta_amb),   R = R_ref (1 + alpha (theta - theta_ref))
"""

from __future__ import annotations

import numpy as np
from numba import njit

from imdrive.kernels.layout import (
    P_ALPHA1,
    P_ALPHA2,
    P_B,
    P_J,
    P_LL1,
    P_LL2,
    P_LOAD_FAN,
    P_LOAD_VISC,
    P_M,
    P_MECH_MODE,
    P_NP,
    P_RTH1,
    P_RTH2,
    P_TAU1,
    P_TAU2,
    P_THERMAL,
    P_THETA_AMB,
    P_THETA_REF,
    X_E_CU,
    X_E_EM,
    X_E_IN,
    X_E_LOAD,
    X_PSI_R_A,
    X_PSI_R_B,
    X_PSI_S_A,
    X_PSI_S_B,
    X_TH1,
    X_TH2,
    X_THETA_M,
    X_W_M,
)

# ------------------------------------------------------------------------------------------
# compiled kernels


@njit(cache=True)
def currents_from_fluxes(psi_s_a, psi_s_b, psi_r_a, psi_r_b, L1, L2, M):
    """Stator and rotor currents from the flux linkages, A.

    Inverts ``[psi_s; psi_r] = [[L1, M], [M, L2]] [i_s; i_r]``.
    """
    inv_d = 1.0 / (L1 * L2 - M * M)
    i_s_a = (L2 * psi_s_a - M * psi_r_a) * inv_d
    i_s_b = (L2 * psi_s_b - M * psi_r_b) * inv_d
    i_r_a = (L1 * psi_r_a - M * psi_s_a) * inv_d
    i_r_b = (L1 * psi_r_b - M * psi_s_b) * inv_d
    return i_s_a, i_s_b, i_r_a, i_r_b


@njit(cache=True)
def winding_resistances(x, par, R1_base, R2_base):
    """Actual R1, R2 (ohm): the profile-scaled base values times the thermal factor."""
    if par[P_THERMAL] != 0.0:
        R1 = R1_base * (1.0 + par[P_ALPHA1] * (x[X_TH1] - par[P_THETA_REF]))
        R2 = R2_base * (1.0 + par[P_ALPHA2] * (x[X_TH2] - par[P_THETA_REF]))
        return R1, R2
    return R1_base, R2_base


@njit(cache=True)
def load_torque(par, TL0, w_m):
    """Load torque T_L = T0(t) + b w_m + k_fan w_m |w_m|, N m (positive opposes forward motion)."""
    return TL0 + par[P_LOAD_VISC] * w_m + par[P_LOAD_FAN] * w_m * abs(w_m)


@njit(cache=True)
def electromagnetic_torque(psi_s_a, psi_s_b, i_s_a, i_s_b, n_p):
    """T_e = 1.5 n_p (psi_s x i_s), N m."""
    return 1.5 * n_p * (psi_s_a * i_s_b - psi_s_b * i_s_a)


@njit(cache=True)
def machine_derivative(x, v_a, v_b, R1_base, R2_base, TL0, par, dx):
    """Time derivative of the plant state (writes ``dx``).

    Parameters
    ----------
    x : float64[NX]
        Plant state (layout ``X_*``).
    v_a, v_b : float
        Stator voltage space vector applied by the inverter, V.
    R1_base, R2_base : float
        Resistances at the reference temperature, already scaled by their time profiles, ohm.
    TL0 : float
        Time-dependent part of the load torque, N m.
    par : float64[N_PAR]
    dx : float64[NX]
        Output.
    """
    L1 = par[P_LL1] + par[P_M]
    L2 = par[P_LL2] + par[P_M]
    M = par[P_M]
    n_p = par[P_NP]
    psi_s_a = x[X_PSI_S_A]
    psi_s_b = x[X_PSI_S_B]
    psi_r_a = x[X_PSI_R_A]
    psi_r_b = x[X_PSI_R_B]
    w_m = x[X_W_M]
    R1, R2 = winding_resistances(x, par, R1_base, R2_base)
    i_s_a, i_s_b, i_r_a, i_r_b = currents_from_fluxes(psi_s_a, psi_s_b, psi_r_a, psi_r_b, L1, L2, M)
    w_r = n_p * w_m
    dx[X_PSI_S_A] = v_a - R1 * i_s_a
    dx[X_PSI_S_B] = v_b - R1 * i_s_b
    dx[X_PSI_R_A] = -R2 * i_r_a - w_r * psi_r_b
    dx[X_PSI_R_B] = -R2 * i_r_b + w_r * psi_r_a
    T_e = electromagnetic_torque(psi_s_a, psi_s_b, i_s_a, i_s_b, n_p)
    T_L = load_torque(par, TL0, w_m)
    if par[P_MECH_MODE] == 0.0:
        dx[X_W_M] = (T_e - T_L - par[P_B] * w_m) / par[P_J]
    else:  # speed imposed: the engine writes x[X_W_M] from its profile every period
        dx[X_W_M] = 0.0
    dx[X_THETA_M] = w_m
    p_cu1 = 1.5 * R1 * (i_s_a * i_s_a + i_s_b * i_s_b)
    p_cu2 = 1.5 * R2 * (i_r_a * i_r_a + i_r_b * i_r_b)
    if par[P_THERMAL] != 0.0:
        dx[X_TH1] = (par[P_RTH1] * p_cu1 - (x[X_TH1] - par[P_THETA_AMB])) / par[P_TAU1]
        dx[X_TH2] = (par[P_RTH2] * p_cu2 - (x[X_TH2] - par[P_THETA_AMB])) / par[P_TAU2]
    else:
        dx[X_TH1] = 0.0
        dx[X_TH2] = 0.0
    dx[X_E_IN] = 1.5 * (v_a * i_s_a + v_b * i_s_b)
    dx[X_E_CU] = p_cu1 + p_cu2
    dx[X_E_EM] = T_e * w_m
    dx[X_E_LOAD] = (T_L + par[P_B] * w_m) * w_m


@njit(cache=True)
def magnetic_energy(x, par):
    """Energy stored in the magnetic field, 1.5 * 0.5 * (psi_s.i_s + psi_r.i_r), J."""
    L1 = par[P_LL1] + par[P_M]
    L2 = par[P_LL2] + par[P_M]
    i_s_a, i_s_b, i_r_a, i_r_b = currents_from_fluxes(
        x[X_PSI_S_A], x[X_PSI_S_B], x[X_PSI_R_A], x[X_PSI_R_B], L1, L2, par[P_M]
    )
    return 0.75 * (
        x[X_PSI_S_A] * i_s_a + x[X_PSI_S_B] * i_s_b + x[X_PSI_R_A] * i_r_a + x[X_PSI_R_B] * i_r_b
    )


def initial_state(theta_init_C: float = 20.0, w_m0: float = 0.0) -> np.ndarray:
    """Plant state at rest, demagnetised, windings at ``theta_init_C``."""
    from imdrive.kernels.layout import NX

    x = np.zeros(NX)
    x[X_W_M] = w_m0
    x[X_TH1] = theta_init_C
    x[X_TH2] = theta_init_C
    return x
