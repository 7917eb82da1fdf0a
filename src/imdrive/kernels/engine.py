"""The simulation loop: a discrete controller at period Ts driving the continuous plant.

Each control period ``[t_k, t_k + Ts)``:

1. sample the plant (current through the sensors, speed) at ``t_k``;
2. run the estimator (MRAS) and the R2 compensator (which acts at its own period);
3. run the controller (open-loop voltage or field-oriented control) -> voltage reference;
4. the inverter turns it into voltage segments, held over the period (zero-order hold);
5. integrate the plant over the period, segment by segment
   (:func:`imdrive.kernels.machine.integrate_segment`).

A drive is two named tuples of record arrays (one record dtype per block, see
:mod:`imdrive.kernels.records`): :class:`DriveParams` (constant over a run) and
:class:`DriveState` (updated in place). Each array has one row per drive, so the same compiled
:func:`run_drive` serves one drive (``N = 1``, ``i = 0``) and the batch (:mod:`.batch`).
"""

from __future__ import annotations

import cmath
import math
from typing import NamedTuple

import numpy as np
from numba import njit

from imdrive.kernels import compensator, estimators, ifoc, inverter, machine, model, sensors
from imdrive.kernels.bridge import switching_period  # noqa: F401  (re-exported: old path)
from imdrive.kernels.compensator import (
    compensator_gate_sample,
    compensator_step,
    demodulate,
    injection_headroom,
    injection_sine,
    log_compensator,
)
from imdrive.kernels.estimators.afo import afo_step
from imdrive.kernels.estimators.ekf import ekf_step
from imdrive.kernels.estimators.mras import (
    log_mras,
    mras_r1_standstill,
    mras_r1_step,
    mras_step,
)
from imdrive.kernels.estimators.reactive_mras import reactive_mras_step
from imdrive.kernels.ifoc import (
    dead_time_feedforward,
    field_weakening,
    foc_step,
    log_control,
    open_loop_voltage,
)
from imdrive.kernels.inverter import (
    INV_SWITCHING,
    MAX_EVENTS,
    MAX_SEGMENTS,
    inverter_segments,
    limit_magnitude,
)
from imdrive.kernels.machine import (
    PLANT_STATE,
    integrate_segment,
    log_plant,
    stator_current,
)
from imdrive.kernels.profiles import (
    PR_FLUX_REF,
    PR_FREQ,
    PR_LOAD,
    PR_R1_SCALE,
    PR_R2_SCALE,
    PR_SPEED_IMPOSED,
    PR_SPEED_REF,
    PR_V_AMP,
    profile_at,
)
from imdrive.kernels.records import b1, c16, f8, i8, record_dtype
from imdrive.kernels.sensors import measure_current

DRIVE_OPEN_LOOP = 0
DRIVE_FOC = 1

# speed estimators (SIM_PARAMS.estimator); the one selected feeds the controller when
# sensorless and is the one logged as speed_est
EST_MRAS = 0  # Schauder's MRAS (estimators/mras.py), also run with measured feedback
EST_REACTIVE_MRAS = 1  # estimators/reactive_mras.py
EST_AFO = 2  # estimators/afo.py
EST_EKF = 3  # estimators/ekf.py
#: control.speed_feedback -> SIM_PARAMS.estimator ("measured" runs the MRAS, as before)
ESTIMATOR_CODES = {
    "measured": EST_MRAS,
    "mras": EST_MRAS,
    "reactive-mras": EST_REACTIVE_MRAS,
    "afo": EST_AFO,
    "ekf": EST_EKF,
}

# status codes returned by the engine
S_OK = 0
S_NAN = 1
S_CURRENT = 2
S_SPEED = 3

#: Parameters of the loop itself.
SIM_PARAMS = record_dtype(
    [
        ("Ts", f8),  # control period, s
        ("nsub", i8),  # RK4 sub-steps per segment
        ("i_lim", f8),  # divergence bound on |i_s|, A
        ("w_lim", f8),  # divergence bound on |w_m|, rad/s
        ("mode", i8),  # DRIVE_OPEN_LOOP or DRIVE_FOC
        ("sensorless", b1),  # speed feedback: the MRAS estimate instead of the measured speed
        ("delay", i8),  # computation delay, periods: 0, or 1 (the reference of sample k acts
        # over the next period, as on a DSP)
        ("estimator", i8),  # EST_MRAS (default), EST_REACTIVE_MRAS, EST_AFO, EST_EKF
        ("flux_inj_amp", f8),  # flux-command injection: relative amplitude (0: off)
        ("flux_inj_freq", f8),  # its frequency, Hz
    ]
)

#: What the controller keeps from one sample to the next.
SAMPLE_STATE = record_dtype(
    [
        ("v_prev_ab", c16),  # voltage the controller commanded for the last period, V
        ("i_prev_ab", c16),  # current measured at the last sample, A
        ("v_hold_ab", c16),  # with a one-period delay: the reference waiting for the next period
        ("dv_hold_ab", c16),  # and the dead-time compensation it contains, V
    ]
)

#: One log row: the sample time, then every block's declared fields (SI units).
LOG_FIELDS = (
    ("time",)
    + machine.LOG_FIELDS
    + inverter.LOG_FIELDS
    + sensors.LOG_FIELDS
    + ifoc.LOG_FIELDS
    + estimators.mras.LOG_FIELDS
    + model.LOG_FIELDS
    + compensator.LOG_FIELDS
)
LOG = record_dtype([(name, f8) for name in LOG_FIELDS])


class DriveParams(NamedTuple):
    """A drive's constant inputs; every field has one row per drive (first axis)."""

    sim: np.ndarray  # SIM_PARAMS
    plant: np.ndarray  # machine.PLANT_PARAMS
    inverter: np.ndarray  # inverter.INVERTER_PARAMS
    sensor: np.ndarray  # sensors.SENSOR_PARAMS
    control: np.ndarray  # ifoc.CONTROL_PARAMS
    mras: np.ndarray  # estimators.mras.MRAS_PARAMS
    comp: np.ndarray  # compensator.COMPENSATOR_PARAMS
    rmras: np.ndarray  # estimators.reactive_mras.REACTIVE_MRAS_PARAMS
    afo: np.ndarray  # estimators.afo.AFO_PARAMS
    ekf: np.ndarray  # estimators.ekf.EKF_PARAMS
    prof_t: np.ndarray  # float64[N, N_PROF, K] profile breakpoint times, s
    prof_v: np.ndarray  # float64[N, N_PROF, K] profile values (SI)
    prof_n: np.ndarray  # int64[N, N_PROF] breakpoints per profile
    tables: np.ndarray  # float64[T, 13, 13] fuzzy lookup tables
    table_idx: np.ndarray  # int64[N] each drive's table


class DriveState(NamedTuple):
    """A drive's state, updated in place; every field has one row per drive."""

    plant: np.ndarray  # machine.PLANT_STATE
    sample: np.ndarray  # SAMPLE_STATE
    model: np.ndarray  # model.MODEL_STATE
    control: np.ndarray  # ifoc.CONTROL_STATE
    mras: np.ndarray  # estimators.mras.MRAS_STATE
    comp: np.ndarray  # compensator.COMPENSATOR_STATE
    inverter: np.ndarray  # inverter.INVERTER_STATE
    rmras: np.ndarray  # estimators.reactive_mras.REACTIVE_MRAS_STATE
    afo: np.ndarray  # estimators.afo.AFO_STATE
    ekf: np.ndarray  # estimators.ekf.EKF_STATE


@njit(cache=True)
def _finite_state(smp, mdl, ctl, est, cmp):
    """Whether every controller-side state is finite (a NaN there means divergence)."""
    f = math.isfinite
    c = cmath.isfinite
    ok = c(smp.v_prev_ab) and c(smp.i_prev_ab)
    ok = ok and f(mdl.R1_hat) and f(mdl.R2_hat) and f(mdl.Ll1_hat) and f(mdl.Ll2_hat)
    ok = ok and f(mdl.M_hat)
    ok = ok and f(ctl.theta_e) and f(ctl.w_e) and f(ctl.int_w) and c(ctl.int_dq)
    ok = ok and c(ctl.i_ref_dq) and c(ctl.i_s_dq) and f(ctl.psi_hat) and f(ctl.theta_ol)
    ok = ok and c(est.lam_v_ab) and c(est.lam_i_ab) and c(est.lam_f_ab) and f(est.int_e)
    ok = ok and f(est.w_r_hat) and c(est.e_dq0)
    ok = ok and f(cmp.E_prev) and f(cmp.cr) and f(cmp.acc) and f(cmp.inj_phase)
    return ok and f(cmp.demod)


@njit(cache=True)
def run_drive(P, S, i, n_steps, log, log_every, k0=0, final=True):
    """Simulate drive ``i`` of ``P``/``S`` for ``n_steps`` control periods (``S`` in place).

    Parameters
    ----------
    P : DriveParams
    S : DriveState
        State at the start; final state on return.
    i : int
        The drive's row in every array of ``P`` and ``S``.
    n_steps : int
        Number of control periods.
    log : LOG[n_rows]
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
    sim = P.sim[i]
    pp = P.plant[i]
    pinv = P.inverter[i]
    psen = P.sensor[i]
    pc = P.control[i]
    pm = P.mras[i]
    pk = P.comp[i]
    pt = P.prof_t[i]
    pv = P.prof_v[i]
    pn = P.prof_n[i]
    table = P.tables[P.table_idx[i]]
    x = S.plant[i]
    sinv = S.inverter[i]
    smp = S.sample[i]
    mdl = S.model[i]
    ctl = S.control[i]
    est = S.mras[i]
    cmp = S.comp[i]
    est_code = sim.estimator
    p_rm = P.rmras[i]
    s_rm = S.rmras[i]
    p_afo = P.afo[i]
    s_afo = S.afo[i]
    p_ekf = P.ekf[i]
    s_ekf = S.ekf[i]
    flux_inj = sim.flux_inj_amp != 0.0
    r1_adapt = pm.k_R1 > 0.0
    headroom = pk.inj_v_hi > 0.0

    Ts = sim.Ts
    nsub = max(sim.nsub, 1)
    n_p = pp.n_p
    foc = sim.mode == DRIVE_FOC
    sensorless = sim.sensorless
    injecting = pk.inj_amp != 0.0
    switching = pinv.model == INV_SWITCHING
    delayed = sim.delay > 0
    dtc = pc.dtc_u > 0.0
    Vdc_meas = psen.vdc_gain * pinv.Vdc
    n_rows = log.shape[0]

    work = np.empty(5, dtype=PLANT_STATE)  # RK4 scratch
    seg_dt = np.empty(MAX_SEGMENTS)
    seg_va = np.empty(MAX_SEGMENTS)
    seg_vb = np.empty(MAX_SEGMENTS)
    ev = np.empty((3, MAX_EVENTS))
    no_trace = np.empty((0, 3))

    for k in range(n_steps + 1 if final else n_steps):
        t = (k0 + k) * Ts
        if pp.speed_imposed:
            x.w_m = profile_at(pt, pv, pn, PR_SPEED_IMPOSED, t)
        R1b = pp.R1 * profile_at(pt, pv, pn, PR_R1_SCALE, t)
        R2b = pp.R2 * profile_at(pt, pv, pn, PR_R2_SCALE, t)
        TL0 = profile_at(pt, pv, pn, PR_LOAD, t)

        # --- sample
        i_s_a, i_s_b = stator_current(pp, x)
        i_meas_a, i_meas_b = measure_current(psen, i_s_a, i_s_b, k0 + k)
        w_m = x.w_m

        # --- estimator, controller
        w_ref = 0.0
        theta_k = ctl.theta_e  # the controller's d-axis angle at this sample
        w_hat = 0.0  # the selected estimator's speed, electrical rad/s
        if foc:
            v_pa = smp.v_prev_ab.real
            v_pb = smp.v_prev_ab.imag
            if est_code == EST_MRAS:
                mras_step(
                    pm,
                    mdl,
                    est,
                    v_pa,
                    v_pb,
                    smp.i_prev_ab.real,
                    smp.i_prev_ab.imag,
                    i_meas_a,
                    i_meas_b,
                    theta_k,
                    Ts,
                )
                w_hat = est.w_r_hat
            elif est_code == EST_REACTIVE_MRAS:
                reactive_mras_step(
                    p_rm,
                    mdl,
                    s_rm,
                    v_pa,
                    v_pb,
                    smp.i_prev_ab.real,
                    smp.i_prev_ab.imag,
                    i_meas_a,
                    i_meas_b,
                    Ts,
                )
                w_hat = s_rm.w_r_hat
            elif est_code == EST_AFO:
                afo_step(p_afo, mdl, s_afo, v_pa, v_pb, i_meas_a, i_meas_b, Ts)
                w_hat = s_afo.w_r_hat
            else:
                ekf_step(p_ekf, mdl, s_ekf, v_pa, v_pb, i_meas_a, i_meas_b, Ts)
                w_hat = s_ekf.w_r_hat
            i_inj = 0.0
            v_use = abs(smp.v_prev_ab) / (Vdc_meas / math.sqrt(3.0))
            if injecting:
                ph0 = cmp.inj_phase
                sine = injection_sine(pk, cmp, t, Ts)
                # the cosine only for the filter-compensated detection (one cos per period)
                cosine = math.cos(ph0) if pk.inj_hp_wc > 0.0 and t >= pk.inj_t_on else 0.0
                demodulate(pk, cmp, est.e_dq0, sine, cosine, ctl.w_e, Ts)
                a_inj = 1.0
                if headroom:  # issue 10: the injection backs off near the voltage limit
                    wrapped = cmp.inj_phase < ph0
                    a_inj = injection_headroom(pk, cmp, v_use, ctl.fw_cut > 1e-3, wrapped)
                i_inj = a_inj * pk.inj_amp * sine
            # issue 10: online R1 beside the MRAS; with the compensator's gating, held from its
            # start until it first updates and whenever it freezes (transients)
            if pm.R1_dc and est_code == EST_MRAS:  # issue 10: the DC test at every start
                mras_r1_standstill(
                    pm,
                    mdl,
                    est,
                    v_pa,
                    v_pb,
                    smp.i_prev_ab.real,
                    smp.i_prev_ab.imag,
                    i_meas_a,
                    i_meas_b,
                    profile_at(pt, pv, pn, PR_SPEED_REF, t),
                    ctl.w_e,
                    Ts,
                )
            r1_hold = pk.enabled and pk.gate and (t < pk.t_on or cmp.frozen != 0.0)
            if r1_adapt and est_code == EST_MRAS and not r1_hold:
                # the injected sinusoid (flux-current axis) taken out of the current
                ia_dc = i_meas_a - i_inj * math.cos(theta_k)
                ib_dc = i_meas_b - i_inj * math.sin(theta_k)
                mras_r1_step(pm, mdl, est, ia_dc, ib_dc, ctl.w_e, ctl.i_ref_dq.imag, Ts)
            if pk.enabled:
                if pk.gate and t >= pk.t_on:  # issue 10: the compensator's gating signals
                    w_fb_g = est.w_r_hat / n_p if sensorless else w_m
                    w_ref_g = profile_at(pt, pv, pn, PR_SPEED_REF, t)
                    compensator_gate_sample(
                        pk, cmp, w_ref_g, w_fb_g, ctl.i_ref_dq.imag, v_use, ctl.w_e
                    )
                compensator_step(pk, cmp, mdl, table, est.e_dq0.real, t, k0 + k, ctl.w_e)
            w_ref = profile_at(pt, pv, pn, PR_SPEED_REF, t)
            psi_ref = profile_at(pt, pv, pn, PR_FLUX_REF, t)
            if pc.fw:  # issue 10: field weakening above base speed (voltage feedback)
                psi_ref *= field_weakening(pc, ctl, v_use, Ts)
            if flux_inj:  # excitation for R2 adaptation (Kubota & Matsuse 1994)
                psi_ref *= 1.0 + sim.flux_inj_amp * math.sin(2.0 * math.pi * sim.flux_inj_freq * t)
            w_fb = w_hat / n_p if sensorless else w_m
            v_ref_a, v_ref_b = foc_step(
                pc, mdl, ctl, i_meas_a, i_meas_b, w_fb, w_ref, psi_ref, i_inj, Ts
            )
        else:
            v_amp = profile_at(pt, pv, pn, PR_V_AMP, t)
            f_Hz = profile_at(pt, pv, pn, PR_FREQ, t)
            v_ref_a, v_ref_b = open_loop_voltage(ctl, v_amp, f_Hz, Ts)

        dv_a = 0.0
        dv_b = 0.0
        if dtc:  # dead-time compensation, on the measured current
            dv_a, dv_b = dead_time_feedforward(pc, i_meas_a, i_meas_b)
            v_ref_a += dv_a
            v_ref_b += dv_b
        v_log_a = v_ref_a  # the reference of this sample, logged
        v_log_b = v_ref_b
        if delayed:  # the reference of the last sample acts now, this one next period
            held = smp.v_hold_ab
            held_dv = smp.dv_hold_ab
            smp.v_hold_ab = complex(v_ref_a, v_ref_b)
            smp.dv_hold_ab = complex(dv_a, dv_b)
            v_ref_a = held.real
            v_ref_b = held.imag
            dv_a = held_dv.real
            dv_b = held_dv.imag

        if switching:
            # what the controller commands and believes it applies over this period
            v_cmd_a, v_cmd_b = limit_magnitude(v_ref_a, v_ref_b, Vdc_meas / math.sqrt(3.0))
            v_app_a = v_cmd_a  # replaced by the true average once the period is integrated
            v_app_b = v_cmd_b
        else:
            # the DC-link sensor's gain error scales what the bridge really applies
            k_dc = pinv.Vdc / Vdc_meas
            if k_dc != 1.0:
                v_ref_a *= k_dc
                v_ref_b *= k_dc
            n_seg = inverter_segments(
                pinv, v_ref_a, v_ref_b, i_s_a, i_s_b, Ts, seg_dt, seg_va, seg_vb
            )
            v_app_a = 0.0
            v_app_b = 0.0
            for s in range(n_seg):
                v_app_a += seg_dt[s] * seg_va[s]
                v_app_b += seg_dt[s] * seg_vb[s]
            v_app_a /= Ts
            v_app_b /= Ts
            v_cmd_a, v_cmd_b = limit_magnitude(v_ref_a, v_ref_b, pinv.Vdc / math.sqrt(3.0))
            v_cmd_a = (Ts * v_cmd_a) / Ts  # the 0.1 rounding of a one-segment average
            v_cmd_b = (Ts * v_cmd_b) / Ts
            if k_dc != 1.0:
                v_cmd_a /= k_dc
                v_cmd_b /= k_dc
        # the controller knows the voltage it commanded for this period (used by the MRAS);
        # the dead-time compensation is not part of it: it is meant to cancel the dead time's
        # loss, so the commanded voltage less the compensation is the controller's best
        # estimate of what reaches the terminals
        if dtc:
            smp.v_prev_ab = complex(v_cmd_a - dv_a, v_cmd_b - dv_b)
        else:
            smp.v_prev_ab = complex(v_cmd_a, v_cmd_b)
        smp.i_prev_ab = complex(i_meas_a, i_meas_b)

        # --- log
        if log_every > 0 and k % log_every == 0:
            r = k // log_every
            if r < n_rows:
                row = log[r]
                row.time = t
                log_plant(row, pp, x, i_s_a, i_s_b, TL0, R1b, R2b)
                row.v_alpha = v_app_a
                row.v_beta = v_app_b
                row.v_ref_alpha = v_log_a
                row.v_ref_beta = v_log_b
                row.i_alpha_meas = i_meas_a
                row.i_beta_meas = i_meas_b
                log_control(row, ctl, w_ref, theta_k)
                log_mras(row, est, n_p)
                if est_code != EST_MRAS:
                    row.speed_est = w_hat / n_p
                row.R2_est = mdl.R2_hat
                row.R1_est = mdl.R1_hat
                log_compensator(row, cmp)
        if k == n_steps:
            break

        # --- plant over the period
        if switching:
            v_app_a, v_app_b = switching_period(
                pinv,
                sinv,
                pp,
                x,
                v_cmd_a,
                v_cmd_b,
                Vdc_meas,
                R1b,
                R2b,
                TL0,
                Ts,
                nsub,
                work,
                ev,
                no_trace,
            )
            if log_every > 0 and k % log_every == 0 and k // log_every < n_rows:
                log[k // log_every].v_alpha = v_app_a  # the true average, known only now
                log[k // log_every].v_beta = v_app_b
        else:
            for s in range(n_seg):
                integrate_segment(pp, x, seg_va[s], seg_vb[s], R1b, R2b, TL0, seg_dt[s], nsub, work)

        # --- divergence
        i_s_a, i_s_b = stator_current(pp, x)
        i_mag = math.sqrt(i_s_a * i_s_a + i_s_b * i_s_b)
        if not (math.isfinite(i_mag) and math.isfinite(x.w_m)):
            return S_NAN, k + 1
        if not _finite_state(smp, mdl, ctl, est, cmp):
            return S_NAN, k + 1
        if not math.isfinite(w_hat):
            return S_NAN, k + 1
        if i_mag > sim.i_lim:
            return S_CURRENT, k + 1
        if abs(x.w_m) > sim.w_lim:
            return S_SPEED, k + 1
    return S_OK, n_steps
