"""The stages of one control period, each a compiled function on records.

:func:`imdrive.kernels.engine.run_drive` calls them in this order for each period
``[t_k, t_k + Ts)``:

1. :func:`measure` -- profiles at ``t_k``, the plant's current through the sensors;
2. :func:`estimate` -- the R2 compensator's injection, the selected speed estimator (through
   the registry's generic :func:`~imdrive.kernels.estimators.registry.estimator_step`), the
   synchronous detection and the compensator's decision;
3. :func:`control` -- field-oriented control (or the open-loop voltage), dead-time
   feed-forward, the computation delay -> voltage reference;
4. :func:`modulate` -- the inverter: the voltage the controller commands and believes applied
   (kept for the next estimator step), and the average model's segments;
5. :func:`log_row` -- one log row every ``log_every`` periods;
6. :func:`plant` -- the plant integrated over the period (segments or the switching bridge);
7. :func:`check` -- divergence.

What one stage hands the next lives in a :data:`PERIOD` record (the period's signals, SI
units, space vectors complex in the stationary frame ``_ab`` or the controller's ``_dq``).
Stored part by part from floats, the values are exactly those of the one-function loop they
replace, so every result is bit for bit the same.
"""

from __future__ import annotations

import cmath
import math

from numba import njit

from imdrive.kernels.bridge import switching_period
from imdrive.kernels.compensator import (
    compensator_gate_sample,
    compensator_step,
    demodulate,
    injection_sine,
    log_compensator,
)
from imdrive.kernels.compensator_range import (
    headroom_weakening_input,
    injection_headroom,
    thermal_step,
)
from imdrive.kernels.estimators.registry import estimator_finite, estimator_log, estimator_step
from imdrive.kernels.ifoc import (
    dead_time_feedforward,
    field_weakening,
    foc_step,
    log_control,
    open_loop_voltage,
)
from imdrive.kernels.inverter import inverter_segments, limit_magnitude
from imdrive.kernels.machine import integrate_segment, log_plant, stator_current
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

S_OK = 0
S_NAN = 1
S_CURRENT = 2
S_SPEED = 3

#: The signals of one period, handed from stage to stage.
PERIOD = record_dtype(
    [
        ("t", f8),  # time of the sample, s
        ("k", i8),  # index of the sample since the start of the run
        ("R1_base", f8),  # the plant's resistances before temperature, ohm
        ("R2_base", f8),
        ("T_L0", f8),  # load torque profile, N m
        ("w_imposed", f8),  # the imposed speed profile, mechanical rad/s
        ("w_ref_prof", f8),  # the speed reference profile, mechanical rad/s
        ("psi_ref_prof", f8),  # the rotor-flux reference profile, Wb
        ("v_amp_prof", f8),  # the open-loop voltage amplitude profile, V
        ("f_prof", f8),  # the open-loop frequency profile, Hz
        ("i_s_ab", c16),  # the plant's stator current at the sample, A
        ("i_meas_ab", c16),  # the measured current, A
        ("w_ref", f8),  # speed reference, mechanical rad/s
        ("theta_k", f8),  # the controller's d-axis angle at this sample, rad
        ("w_r_hat", f8),  # the selected estimator's speed, electrical rad/s
        ("e_dq0", c16),  # its flux error in the controller's frame, Wb
        ("i_inj", f8),  # the R2 compensator's injected d-axis current, A
        ("v_use", f8),  # last period's voltage over Vdc_meas/sqrt 3
        ("v_fw", f8),  # the voltage use the field weakening sees (the injection's headroom)
        ("v_ref_ab", c16),  # the reference that acts this period (after the delay), V
        ("v_log_ab", c16),  # the reference computed at this sample (logged), V
        ("dv_ab", c16),  # the dead-time compensation contained in v_ref_ab, V
        ("v_cmd_ab", c16),  # what the controller commands and believes applied, V
        ("v_app_ab", c16),  # the period-average voltage at the terminals, V
        ("n_seg", i8),  # segments of the average model
        ("i_next_ab", c16),  # the plant's current after the period (check), A: the next
        ("have_next", b1),  # sample's, so a saturated machine's curve is solved once a period
    ]
)


@njit(cache=True, inline="always")
def profiles(pp, pt, pv, pn, pr, foc):
    """The profiles the drive reads at ``pr.t`` into ``pr`` (the stages after it read no
    profile array): the references of field-oriented control, or the open-loop voltage."""
    t = pr.t
    if pp.speed_imposed:
        pr.w_imposed = profile_at(pt, pv, pn, PR_SPEED_IMPOSED, t)
    pr.R1_base = pp.R1 * profile_at(pt, pv, pn, PR_R1_SCALE, t)
    pr.R2_base = pp.R2 * profile_at(pt, pv, pn, PR_R2_SCALE, t)
    pr.T_L0 = profile_at(pt, pv, pn, PR_LOAD, t)
    if foc:
        pr.w_ref_prof = profile_at(pt, pv, pn, PR_SPEED_REF, t)
        pr.psi_ref_prof = profile_at(pt, pv, pn, PR_FLUX_REF, t)
    else:
        pr.v_amp_prof = profile_at(pt, pv, pn, PR_V_AMP, t)
        pr.f_prof = profile_at(pt, pv, pn, PR_FREQ, t)


@njit(cache=True, inline="always")
def measure(pp, psen, x, pr):
    """The plant's current and the current sensors at ``pr.t`` (fills ``pr``)."""
    if pp.speed_imposed:
        x.w_m = pr.w_imposed
    if pr.have_next:  # the current the last check computed from this same state
        i_s_alpha = pr.i_next_ab.real
        i_s_beta = pr.i_next_ab.imag
    else:
        i_s_alpha, i_s_beta = stator_current(pp, x)
    pr.i_s_ab = complex(i_s_alpha, i_s_beta)
    i_meas_alpha, i_meas_beta = measure_current(psen, i_s_alpha, i_s_beta, pr.k)
    pr.i_meas_ab = complex(i_meas_alpha, i_meas_beta)


@njit(cache=True, inline="always")
def estimate(sim, pp, pe, pk, table, x, mdl, ctl, est, cmp, smp, inp, pr, Vdc_meas):
    """The injection, the selected estimator, the detection and the R2 compensator.

    Writes ``pr.w_r_hat``, ``pr.e_dq0``, ``pr.i_inj``, ``pr.v_use``; the estimator's state
    ``est`` and the compensator's ``cmp`` in place, and the controller's model ``mdl`` where
    they adapt it.
    """
    t = pr.t
    Ts = sim.Ts
    pr.v_use = abs(smp.v_prev_ab) / (Vdc_meas / math.sqrt(3.0))
    pr.v_fw = pr.v_use
    sine = 0.0
    cosine = 0.0
    i_inj = 0.0
    if pk.inj_amp != 0.0:
        ph0 = cmp.inj_phase
        sine = injection_sine(pk, cmp, t, Ts)
        # the cosine only for the filter-compensated detection (one cos per period)
        cosine = math.cos(ph0) if pk.inj_hp_wc > 0.0 and t >= pk.inj_t_on else 0.0
        a_inj = 1.0
        if pk.inj_v_hi > 0.0:  # the injection backs off near the voltage limit
            wrapped = cmp.inj_phase < ph0
            a_inj = injection_headroom(pk, cmp, pr.v_use, 1.0 - ctl.fw_cut, wrapped)
        i_inj = a_inj * pk.inj_amp * sine
        if pk.inj_fw and cmp.v_peak_last > 0.0:  # the field weakening leaves it headroom
            pr.v_fw = headroom_weakening_input(pk, cmp, pr.v_use)
    pr.i_inj = i_inj
    w_ref = pr.w_ref_prof

    inp.v_ab = smp.v_prev_ab
    inp.i_prev_ab = smp.i_prev_ab
    inp.i_ab = pr.i_meas_ab
    inp.theta_e = pr.theta_k
    inp.w_e = ctl.w_e
    inp.i_ref_dq = ctl.i_ref_dq
    inp.w_ref = w_ref
    inp.i_inj = i_inj
    # R1 adaptation held from the compensator's start until it first updates and whenever
    # its gating freezes it (transients)
    inp.hold_R1 = pk.enabled and pk.gate and (t < pk.t_on or cmp.frozen != 0.0)
    inp.Ts = Ts
    inp.t = t
    w_r_hat, e_dq0 = estimator_step(pe, mdl, est, inp)
    pr.w_r_hat = w_r_hat
    pr.e_dq0 = e_dq0

    if pk.inj_amp != 0.0:
        demodulate(pk, cmp, e_dq0, sine, cosine, ctl.w_e, Ts)
    if pk.enabled:
        if pk.gate and t >= pk.t_on:  # the compensator's gating signals
            w_fb_g = w_r_hat / pp.n_p if sim.sensorless else x.w_m
            compensator_gate_sample(pk, cmp, w_ref, w_fb_g, ctl.i_ref_dq.imag, pr.v_use, ctl.w_e)
        compensator_step(pk, cmp, mdl, table, e_dq0.real, t, pr.k, ctl.w_e)
        if pk.th_on:  # the rotor thermal model carries R2_hat while it is held
            thermal_step(pk, cmp, mdl, ctl.i_s_dq.imag, t, Ts)


@njit(cache=True, inline="always")
def control(sim, pc, x, mdl, ctl, smp, pr, foc):
    """Field-oriented control (or the open-loop voltage), dead-time feed-forward, delay.

    Writes ``pr.w_ref``, ``pr.v_log_ab`` (the reference of this sample), ``pr.v_ref_ab`` (the
    one that acts this period: the last sample's with a one-period delay) and ``pr.dv_ab``
    (the dead-time compensation it contains).
    """
    t = pr.t
    Ts = sim.Ts
    w_ref = 0.0
    i_meas_alpha = pr.i_meas_ab.real
    i_meas_beta = pr.i_meas_ab.imag
    if foc:
        w_ref = pr.w_ref_prof
        psi_ref = pr.psi_ref_prof
        if pc.fw:  # field weakening above base speed (voltage feedback)
            psi_ref *= field_weakening(pc, ctl, pr.v_fw, Ts)
        if sim.flux_inj_amp != 0.0:  # excitation for R2 adaptation (Kubota & Matsuse 1994)
            psi_ref *= 1.0 + sim.flux_inj_amp * math.sin(2.0 * math.pi * sim.flux_inj_freq * t)
        w_fb = pr.w_r_hat / pc.n_p if sim.sensorless else x.w_m
        v_ref_alpha, v_ref_beta = foc_step(
            pc, mdl, ctl, i_meas_alpha, i_meas_beta, w_fb, w_ref, psi_ref, pr.i_inj, Ts
        )
    else:
        v_amp = pr.v_amp_prof
        f_Hz = pr.f_prof
        v_ref_alpha, v_ref_beta = open_loop_voltage(ctl, v_amp, f_Hz, Ts)
    pr.w_ref = w_ref

    dv_alpha = 0.0
    dv_beta = 0.0
    if pc.dtc_u > 0.0:  # dead-time compensation, on the measured current
        dv_alpha, dv_beta = dead_time_feedforward(pc, i_meas_alpha, i_meas_beta)
        v_ref_alpha += dv_alpha
        v_ref_beta += dv_beta
    pr.v_log_ab = complex(v_ref_alpha, v_ref_beta)
    if sim.delay > 0:  # the reference of the last sample acts now, this one next period
        held = smp.v_hold_ab
        held_dv = smp.dv_hold_ab
        smp.v_hold_ab = complex(v_ref_alpha, v_ref_beta)
        smp.dv_hold_ab = complex(dv_alpha, dv_beta)
        v_ref_alpha = held.real
        v_ref_beta = held.imag
        dv_alpha = held_dv.real
        dv_beta = held_dv.imag
    pr.v_ref_ab = complex(v_ref_alpha, v_ref_beta)
    pr.dv_ab = complex(dv_alpha, dv_beta)


@njit(cache=True, inline="always")
def modulate(pinv, pc, smp, pr, switching, Vdc_meas, seg, Ts):
    """The inverter's part at the sample: commanded voltage, average-model segments.

    Writes ``pr.v_cmd_ab`` (what the controller commands and believes it applies),
    ``pr.v_app_ab`` (the average model's true period average; for the switching bridge the
    command, replaced by :func:`plant` once the period is integrated), ``pr.n_seg`` and the
    segments (``seg``: float64[3, MAX_SEGMENTS], durations and alpha, beta voltages); stores
    the commanded voltage less the dead-time compensation and the measured
    current in ``smp`` for the next estimator step.
    """
    v_ref_alpha = pr.v_ref_ab.real
    v_ref_beta = pr.v_ref_ab.imag
    if switching:
        v_cmd_alpha, v_cmd_beta = limit_magnitude(
            v_ref_alpha, v_ref_beta, Vdc_meas / math.sqrt(3.0)
        )
        pr.v_app_ab = complex(v_cmd_alpha, v_cmd_beta)
        pr.n_seg = 0
    else:
        # the DC-link sensor's gain error scales what the bridge really applies
        k_dc = pinv.Vdc / Vdc_meas
        if k_dc != 1.0:
            v_ref_alpha *= k_dc
            v_ref_beta *= k_dc
        i_s = pr.i_s_ab
        seg_dt = seg[0]
        seg_va = seg[1]
        seg_vb = seg[2]
        n_seg = inverter_segments(
            pinv, v_ref_alpha, v_ref_beta, i_s.real, i_s.imag, Ts, seg_dt, seg_va, seg_vb
        )
        v_app_alpha = 0.0
        v_app_beta = 0.0
        for s in range(n_seg):
            v_app_alpha += seg_dt[s] * seg_va[s]
            v_app_beta += seg_dt[s] * seg_vb[s]
        pr.v_app_ab = complex(v_app_alpha / Ts, v_app_beta / Ts)
        pr.n_seg = n_seg
        v_cmd_alpha, v_cmd_beta = limit_magnitude(
            v_ref_alpha, v_ref_beta, pinv.Vdc / math.sqrt(3.0)
        )
        v_cmd_alpha = (Ts * v_cmd_alpha) / Ts  # rounded as a one-segment average (bit-identical)
        v_cmd_beta = (Ts * v_cmd_beta) / Ts
        if k_dc != 1.0:
            v_cmd_alpha /= k_dc
            v_cmd_beta /= k_dc
    pr.v_cmd_ab = complex(v_cmd_alpha, v_cmd_beta)
    # the controller knows the voltage it commanded for this period (used by the estimator);
    # the dead-time compensation is not part of it: it is meant to cancel the dead time's
    # loss, so the commanded voltage less the compensation is the controller's best estimate
    # of what reaches the terminals
    if pc.dtc_u > 0.0:
        smp.v_prev_ab = complex(v_cmd_alpha - pr.dv_ab.real, v_cmd_beta - pr.dv_ab.imag)
    else:
        smp.v_prev_ab = complex(v_cmd_alpha, v_cmd_beta)
    smp.i_prev_ab = pr.i_meas_ab


@njit(cache=True, inline="always")
def log_row(row, pp, pe, x, mdl, ctl, est, cmp, pr):
    """Write one log row: every block's fields at this sample."""
    row.time = pr.t
    i_s = pr.i_s_ab
    log_plant(row, pp, x, i_s.real, i_s.imag, pr.T_L0, pr.R1_base, pr.R2_base)
    row.v_alpha = pr.v_app_ab.real
    row.v_beta = pr.v_app_ab.imag
    row.v_ref_alpha = pr.v_log_ab.real
    row.v_ref_beta = pr.v_log_ab.imag
    row.i_alpha_meas = pr.i_meas_ab.real
    row.i_beta_meas = pr.i_meas_ab.imag
    log_control(row, ctl, pr.w_ref, pr.theta_k)
    row.speed_est = pr.w_r_hat / pp.n_p
    row.e_d0 = pr.e_dq0.real
    row.e_q0 = pr.e_dq0.imag
    estimator_log(row, pe, est, pp.n_p)
    row.R2_hat = mdl.R2_hat
    row.R1_hat = mdl.R1_hat
    log_compensator(row, cmp)


@njit(cache=True, inline="always")
def plant(pinv, sinv, pp, x, pr, switching, Vdc_meas, nsub, work, ev, no_trace, seg, Ts):
    """Integrate the plant over the period: the average model's segments, or the switching
    bridge between its gate events (then ``pr.v_app_ab`` becomes the true average)."""
    if switching:
        v_cmd = pr.v_cmd_ab
        v_app_alpha, v_app_beta = switching_period(
            pinv,
            sinv,
            pp,
            x,
            v_cmd.real,
            v_cmd.imag,
            Vdc_meas,
            pr.R1_base,
            pr.R2_base,
            pr.T_L0,
            Ts,
            nsub,
            work,
            ev,
            no_trace,
        )
        pr.v_app_ab = complex(v_app_alpha, v_app_beta)
    else:
        for s in range(pr.n_seg):
            integrate_segment(
                pp, x, seg[1, s], seg[2, s], pr.R1_base, pr.R2_base, pr.T_L0, seg[0, s], nsub, work
            )


@njit(cache=True, inline="always")
def _controller_finite(smp, mdl, ctl, cmp):
    """Whether every controller-side state is finite (a NaN there means divergence)."""
    f = math.isfinite
    c = cmath.isfinite
    ok = c(smp.v_prev_ab) and c(smp.i_prev_ab)
    ok = ok and f(mdl.R1_hat) and f(mdl.R2_hat) and f(mdl.Ll1_hat) and f(mdl.Ll2_hat)
    ok = ok and f(mdl.M_hat)
    ok = ok and f(ctl.theta_e) and f(ctl.w_e) and f(ctl.int_w) and c(ctl.int_dq)
    ok = ok and c(ctl.i_ref_dq) and c(ctl.i_s_dq) and f(ctl.psi_hat) and f(ctl.theta_ol)
    ok = ok and f(cmp.E_prev) and f(cmp.cr) and f(cmp.acc) and f(cmp.inj_phase)
    return ok and f(cmp.demod)


@njit(cache=True, inline="always")
def check(sim, pp, x, smp, mdl, ctl, est, cmp, pr):
    """Divergence after the period: ``S_OK`` or ``S_NAN``, ``S_CURRENT``, ``S_SPEED``.

    Keeps the plant's current in ``pr.i_next_ab`` for the next :func:`measure`.
    """
    i_s_alpha, i_s_beta = stator_current(pp, x)
    pr.i_next_ab = complex(i_s_alpha, i_s_beta)
    pr.have_next = True
    i_mag = math.sqrt(i_s_alpha * i_s_alpha + i_s_beta * i_s_beta)
    if not (math.isfinite(i_mag) and math.isfinite(x.w_m)):
        return S_NAN
    if not (_controller_finite(smp, mdl, ctl, cmp) and estimator_finite(est)):
        return S_NAN
    if not math.isfinite(pr.w_r_hat):
        return S_NAN
    if i_mag > sim.i_lim:
        return S_CURRENT
    if abs(x.w_m) > sim.w_lim:
        return S_SPEED
    return S_OK
