"""The simulation loop: a discrete controller at period Ts driving the continuous plant.

Each control period ``[t_k, t_k + Ts)``:

1. sample the plant (current with sensor offset, speed) at ``t_k``;
2. run the estimator (MRAS) and the R2 compensator (which acts at its own period);
3. run the controller (open-loop voltage or field-oriented control) -> voltage reference;
4. the inverter turns it into voltage segments, held over the period (zero-order hold);
5. integrate the plant over the period with ``P_NSUB`` classical RK4 sub-steps per segment.

RK4 rather than an exact discretisation: the plant is nonlinear (speed multiplies flux, the
thermal model makes R depend on state), the fastest electrical mode has ``|lambda| ~ 400 1/s``
so ``|lambda| h ~ 0.04`` at the default 100 us, where RK4's local error is ~1e-9 relative; the
accuracy test against scipy's solve_ivp (tests/test_machine_physics.py) measures it.

:func:`run_drive` simulates one drive; :func:`run_batch` runs N independent drives over the
cores. Both work on the flat arrays of :mod:`imdrive.layout` only.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from imdrive.kernels.compensator import compensator_step, demodulate, injection_sine
from imdrive.kernels.estimators.mras import mras_step
from imdrive.kernels.ifoc import foc_step, open_loop_voltage
from imdrive.kernels.inverter import MAX_SEGMENTS, inverter_segments
from imdrive.kernels.layout import (
    C_DEMOD,
    C_E_D0,
    C_E_Q0,
    C_I_D,
    C_I_PREV_A,
    C_I_PREV_B,
    C_I_Q,
    C_ID_REF,
    C_IQ_REF,
    C_LAM_F_A,
    C_LAM_F_B,
    C_LAM_V_A,
    C_LAM_V_B,
    C_R2_HAT,
    C_THETA_E,
    C_V_PREV_A,
    C_V_PREV_B,
    C_W_HAT,
    L_DEMOD,
    L_E_D0,
    L_E_Q0,
    L_FLUX,
    L_I_A,
    L_I_B,
    L_I_D,
    L_I_Q,
    L_ID_REF,
    L_IQ_REF,
    L_LAM_F_A,
    L_LAM_F_B,
    L_LAM_V_A,
    L_LAM_V_B,
    L_PSI_R_A,
    L_PSI_R_B,
    L_R1,
    L_R2,
    L_R2_HAT,
    L_TE,
    L_TH1,
    L_TH2,
    L_THETA_E,
    L_TIME,
    L_TL,
    L_V_A,
    L_V_B,
    L_W_HAT,
    L_W_M,
    L_W_REF,
    NX,
    P_COMP_ON,
    P_DRIVE_MODE,
    P_I_LIMIT_DIV,
    P_I_OFFSET_A,
    P_I_OFFSET_B,
    P_INJ_AMP,
    P_LL1,
    P_LL2,
    P_M,
    P_MECH_MODE,
    P_NP,
    P_NSUB,
    P_R1,
    P_R2,
    P_SPEED_FB,
    P_TS,
    P_W_LIMIT_DIV,
    PR_FLUX_REF,
    PR_FREQ,
    PR_LOAD,
    PR_R1_SCALE,
    PR_R2_SCALE,
    PR_SPEED_IMPOSED,
    PR_SPEED_REF,
    PR_V_AMP,
    S_CURRENT,
    S_NAN,
    S_OK,
    S_SPEED,
    X_PSI_R_A,
    X_PSI_R_B,
    X_PSI_S_A,
    X_PSI_S_B,
    X_TH1,
    X_TH2,
    X_W_M,
)
from imdrive.kernels.machine import (
    currents_from_fluxes,
    electromagnetic_torque,
    load_torque,
    machine_derivative,
    winding_resistances,
)
from imdrive.kernels.profiles import profile_at

DRIVE_OPEN_LOOP = 0
DRIVE_FOC = 1


@njit(cache=True)
def rk4_segment(x, v_a, v_b, R1b, R2b, TL0, par, dt, nsub, k1, k2, k3, k4, xt):
    """Integrate the plant over ``dt`` with ``nsub`` RK4 steps at constant voltage (in place)."""
    h = dt / nsub
    n = x.shape[0]
    for _ in range(nsub):
        machine_derivative(x, v_a, v_b, R1b, R2b, TL0, par, k1)
        for j in range(n):
            xt[j] = x[j] + 0.5 * h * k1[j]
        machine_derivative(xt, v_a, v_b, R1b, R2b, TL0, par, k2)
        for j in range(n):
            xt[j] = x[j] + 0.5 * h * k2[j]
        machine_derivative(xt, v_a, v_b, R1b, R2b, TL0, par, k3)
        for j in range(n):
            xt[j] = x[j] + h * k3[j]
        machine_derivative(xt, v_a, v_b, R1b, R2b, TL0, par, k4)
        for j in range(n):
            x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])


@njit(cache=True)
def run_drive(par, prof_t, prof_v, prof_n, table, x, c, n_steps, log, log_every, k0=0, final=True):
    """Simulate one drive for ``n_steps`` control periods (``x`` and ``c`` updated in place).

    Parameters
    ----------
    par : float64[N_PAR]
    prof_t, prof_v : float64[N_PROF, K]
    prof_n : int64[N_PROF]
    table : float64[13, 13]
        Fuzzy lookup table of the R2 compensator.
    x : float64[NX]
        Plant state at t = 0; final state on return.
    c : float64[NC]
        Controller state at t = 0; final state on return.
    n_steps : int
        Number of control periods.
    log : float64[n_rows, N_LOG]
        Receives one row every ``log_every`` periods, row r at t = r*log_every*Ts, including
        t = 0 and (when ``n_steps`` is a multiple of ``log_every``) t = n_steps*Ts.
        Pass an array with zero rows for no logging.
    log_every : int
    k0 : int
        Index of the first period: the run continues one that stopped after ``k0`` periods
        (time ``(k0 + k) Ts``), so consecutive calls reproduce one long call exactly.
    final : bool
        Whether to take (and log) the closing sample at ``k = n_steps``. A call that another
        will continue passes False: it returns right after integrating its last period.

    Returns
    -------
    status : int
        ``S_OK`` or the divergence code ``S_NAN``, ``S_CURRENT``, ``S_SPEED``.
    k_end : int
        Number of periods completed in this call (the period where divergence was found).
    """
    Ts = par[P_TS]
    nsub = max(int(par[P_NSUB]), 1)
    M = par[P_M]
    L1 = par[P_LL1] + M
    L2 = par[P_LL2] + M
    n_p = par[P_NP]
    mode = int(par[P_DRIVE_MODE])
    sensorless = par[P_SPEED_FB] != 0.0
    comp_on = par[P_COMP_ON] != 0.0
    injecting = par[P_INJ_AMP] != 0.0
    i_lim = par[P_I_LIMIT_DIV]
    w_lim = par[P_W_LIMIT_DIV]
    n_rows = log.shape[0]

    k1 = np.empty(NX)
    k2 = np.empty(NX)
    k3 = np.empty(NX)
    k4 = np.empty(NX)
    xt = np.empty(NX)
    seg_dt = np.empty(MAX_SEGMENTS)
    seg_va = np.empty(MAX_SEGMENTS)
    seg_vb = np.empty(MAX_SEGMENTS)

    for k in range(n_steps + 1 if final else n_steps):
        t = (k0 + k) * Ts
        if par[P_MECH_MODE] != 0.0:
            x[X_W_M] = profile_at(prof_t, prof_v, prof_n, PR_SPEED_IMPOSED, t)
        R1b = par[P_R1] * profile_at(prof_t, prof_v, prof_n, PR_R1_SCALE, t)
        R2b = par[P_R2] * profile_at(prof_t, prof_v, prof_n, PR_R2_SCALE, t)
        TL0 = profile_at(prof_t, prof_v, prof_n, PR_LOAD, t)

        # --- sample
        i_s_a, i_s_b, i_r_a, i_r_b = currents_from_fluxes(
            x[X_PSI_S_A], x[X_PSI_S_B], x[X_PSI_R_A], x[X_PSI_R_B], L1, L2, M
        )
        i_meas_a = i_s_a + par[P_I_OFFSET_A]
        i_meas_b = i_s_b + par[P_I_OFFSET_B]
        w_m = x[X_W_M]

        # --- estimator, controller
        w_ref = 0.0
        theta_k = c[C_THETA_E]  # the controller's d-axis angle at this sample
        if mode == DRIVE_FOC:
            mras_step(par, c, i_meas_a, i_meas_b, Ts)
            i_inj = 0.0
            if injecting:
                sine = injection_sine(par, c, t, Ts)
                demodulate(par, c, sine, Ts)
                i_inj = par[P_INJ_AMP] * sine
            if comp_on:
                compensator_step(par, c, table, t, k0 + k)
            w_ref = profile_at(prof_t, prof_v, prof_n, PR_SPEED_REF, t)
            psi_ref = profile_at(prof_t, prof_v, prof_n, PR_FLUX_REF, t)
            w_fb = c[C_W_HAT] / n_p if sensorless else w_m
            v_ref_a, v_ref_b = foc_step(par, c, i_meas_a, i_meas_b, w_fb, w_ref, psi_ref, i_inj, Ts)
        else:
            v_amp = profile_at(prof_t, prof_v, prof_n, PR_V_AMP, t)
            f_Hz = profile_at(prof_t, prof_v, prof_n, PR_FREQ, t)
            v_ref_a, v_ref_b = open_loop_voltage(c, v_amp, f_Hz, Ts)

        n_seg = inverter_segments(par, v_ref_a, v_ref_b, i_s_a, i_s_b, Ts, seg_dt, seg_va, seg_vb)
        # the controller knows the period-average voltage it commanded (used by the MRAS)
        v_avg_a = 0.0
        v_avg_b = 0.0
        for s in range(n_seg):
            v_avg_a += seg_dt[s] * seg_va[s]
            v_avg_b += seg_dt[s] * seg_vb[s]
        c[C_V_PREV_A] = v_avg_a / Ts
        c[C_V_PREV_B] = v_avg_b / Ts
        c[C_I_PREV_A] = i_meas_a
        c[C_I_PREV_B] = i_meas_b

        # --- log
        if log_every > 0 and k % log_every == 0:
            r = k // log_every
            if r < n_rows:
                R1, R2 = winding_resistances(x, par, R1b, R2b)
                row = log[r]
                row[L_TIME] = t
                row[L_W_M] = w_m
                row[L_TE] = electromagnetic_torque(x[X_PSI_S_A], x[X_PSI_S_B], i_s_a, i_s_b, n_p)
                row[L_TL] = load_torque(par, TL0, w_m)
                row[L_I_A] = i_s_a
                row[L_I_B] = i_s_b
                row[L_PSI_R_A] = x[X_PSI_R_A]
                row[L_PSI_R_B] = x[X_PSI_R_B]
                row[L_V_A] = c[C_V_PREV_A]
                row[L_V_B] = c[C_V_PREV_B]
                row[L_R1] = R1
                row[L_R2] = R2
                row[L_W_REF] = w_ref
                row[L_W_HAT] = c[C_W_HAT] / n_p
                row[L_ID_REF] = c[C_ID_REF]
                row[L_IQ_REF] = c[C_IQ_REF]
                row[L_I_D] = c[C_I_D]
                row[L_I_Q] = c[C_I_Q]
                row[L_R2_HAT] = c[C_R2_HAT]
                row[L_E_D0] = c[C_E_D0]
                row[L_E_Q0] = c[C_E_Q0]
                row[L_FLUX] = math.sqrt(x[X_PSI_R_A] ** 2 + x[X_PSI_R_B] ** 2)
                row[L_THETA_E] = theta_k
                row[L_TH1] = x[X_TH1]
                row[L_TH2] = x[X_TH2]
                row[L_DEMOD] = c[C_DEMOD]
                row[L_LAM_V_A] = c[C_LAM_V_A]
                row[L_LAM_V_B] = c[C_LAM_V_B]
                row[L_LAM_F_A] = c[C_LAM_F_A]
                row[L_LAM_F_B] = c[C_LAM_F_B]
        if k == n_steps:
            break

        # --- plant over the period
        for s in range(n_seg):
            rk4_segment(
                x, seg_va[s], seg_vb[s], R1b, R2b, TL0, par, seg_dt[s], nsub, k1, k2, k3, k4, xt
            )

        # --- divergence
        i_s_a, i_s_b, i_r_a, i_r_b = currents_from_fluxes(
            x[X_PSI_S_A], x[X_PSI_S_B], x[X_PSI_R_A], x[X_PSI_R_B], L1, L2, M
        )
        i_mag = math.sqrt(i_s_a * i_s_a + i_s_b * i_s_b)
        if not (math.isfinite(i_mag) and math.isfinite(x[X_W_M])):
            return S_NAN, k + 1
        for j in range(c.shape[0]):
            if not math.isfinite(c[j]):
                return S_NAN, k + 1
        if i_mag > i_lim:
            return S_CURRENT, k + 1
        if abs(x[X_W_M]) > w_lim:
            return S_SPEED, k + 1
    return S_OK, n_steps


@njit(cache=True, parallel=True)
def run_batch(par, prof_t, prof_v, prof_n, table, x, c, n_steps, log, log_every, status, k_end):
    """Run ``N`` independent drives in parallel (first axis of every array is the drive).

    ``log`` has shape ``(N, n_rows, N_LOG)`` (``n_rows`` may be 0); ``status`` and ``k_end`` are
    int64[N] outputs.
    """
    N = par.shape[0]
    for n in prange(N):
        s, ke = run_drive(
            par[n],
            prof_t[n],
            prof_v[n],
            prof_n[n],
            table[n],
            x[n],
            c[n],
            n_steps,
            log[n],
            log_every,
        )
        status[n] = s
        k_end[n] = ke
