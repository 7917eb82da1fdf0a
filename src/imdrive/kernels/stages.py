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

What one stage hands the next is a named tuple of the period's signals (:class:`Profiles`,
:class:`Sample`, :class:`Estimate`, :class:`Command`, :class:`Modulation`; SI units, space
vectors complex in the stationary frame ``_ab`` or the controller's ``_dq``). A named tuple is
a value: numba keeps its fields in registers across the inlined stages, as the one-function
loop kept its local variables (a record in memory would be stored and loaded again by every
stage). The values are exactly those of the one-function loop the stages replace, so every
result is bit for bit the same.
"""

from __future__ import annotations

import cmath
import math
from typing import NamedTuple

from imdrive.kernels.bridge import CARRY_FIELDS, bridge_period
from imdrive.kernels.compensator import log_compensator
from imdrive.kernels.compensator_range import headroom_weakening_input
from imdrive.kernels.estimators.registry import (
    EstimatorInput,
    estimator_finite,
    estimator_flux,
    estimator_flux_magnitude,
    estimator_log,
    estimator_step,
)
from imdrive.kernels.features import (
    compiled,
    standstill_r1,
    tracks_r2,
)
from imdrive.kernels.ifoc import (
    dead_time_advance,
    field_weakening,
    foc_step,
    has_feedforward,
    inverter_feedforward,
    log_control,
    open_loop_voltage,
    r1_masked_by_inverter_error,
    standstill_compensation,
)
from imdrive.kernels.inverter import MAX_EVENTS, MAX_SEGMENTS, inverter_segments, limit_magnitude
from imdrive.kernels.inverter_scale import start_from_identified, stator_residual
from imdrive.kernels.jit import njit
from imdrive.kernels.machine import integrate_segment, log_plant, stator_current
from imdrive.kernels.model import model_inductances
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
from imdrive.kernels.r1_standstill import r1_standstill
from imdrive.kernels.r2_law_registry import law_log
from imdrive.kernels.r2_tracking import TrackingInput, excitation, track
from imdrive.kernels.records import f8, record_dtype
from imdrive.kernels.sensors import NOISE_FIELDS, measure_current_drawn
from imdrive.kernels.speed_control import speed_loop_gain

S_OK = 0
S_NAN = 1
S_CURRENT = 2
S_SPEED = 3


class Profiles(NamedTuple):
    """The profiles a drive reads at the sample (:func:`profiles`); those it does not use are 0."""

    w_imposed: float  # the imposed speed, mechanical rad/s
    R1_base: float  # the plant's resistances before temperature, ohm
    R2_base: float
    T_L0: float  # load torque, N m
    w_ref: float  # the speed reference, mechanical rad/s (field-oriented control)
    psi_ref: float  # the rotor-flux reference, Wb (field-oriented control)
    v_amp: float  # the open-loop voltage amplitude, V (open loop)
    f: float  # the open-loop frequency, Hz (open loop)


class Sample(NamedTuple):
    """What the controller samples at ``t`` (:func:`measure`)."""

    t: float  # time of the sample, s
    k: int  # index of the sample since the start of the run
    i_s_ab: complex  # the plant's stator current, A
    i_meas_ab: complex  # the measured current, A
    theta_k: float  # the controller's d-axis angle at this sample, rad


class Estimate(NamedTuple):
    """What :func:`estimate` hands the controller (all 0 in open loop)."""

    w_r_hat: float  # the selected estimator's speed, electrical rad/s
    e_dq0: complex  # its flux error in the controller's frame, Wb
    i_inj: float  # the R2 compensator's injected d-axis current, A
    v_use: float  # last period's voltage over Vdc_meas/sqrt 3
    v_fw: float  # the voltage use the field weakening sees (the injection's headroom)
    hold_R1: bool  # the estimator's R1 adaptation was held this period (its input)
    R1_after: float  # the model's R1_hat right after the estimator's step, ohm (before the
    R2_after: float  # compensator), and its R2_hat: what a recording needs to replay it
    psi_r_ab: complex  # the estimator's rotor-flux estimate, stationary frame, Wb (0j: none)
    psi_mag: float  # an encoder drive's R2_hat-independent flux magnitude, Wb (0: none)


class Command(NamedTuple):
    """What :func:`control` computes at the sample."""

    w_ref: float  # speed reference, mechanical rad/s
    v_log_ab: complex  # the reference computed at this sample (logged), V
    v_ref_ab: complex  # the reference that acts this period (after the delay), V
    dv_ab: complex  # the dead-time compensation contained in v_ref_ab, V
    t_adv: float  # the switching bridge's advance of the gate commands, s


class Modulation(NamedTuple):
    """The inverter's part at the sample (:func:`modulate`)."""

    v_cmd_ab: complex  # what the controller commands and believes applied, V
    v_app_ab: complex  # the period-average voltage at the terminals, V (switching: the command)
    n_seg: int  # segments of the average model
    t_adv: float  # the switching bridge's advance of the gate commands, s


#: The loop's scratch memory, one record for the run. A record is handed to a stage as a
#: pointer, without the reference count an array costs: an array argument of an inlined stage
#: is a new reference, counted up and down (atomically) every period.
SCRATCH = record_dtype(
    [
        ("seg_dt", f8, (MAX_SEGMENTS,)),  # the average model's segments: durations, s
        ("seg_va", f8, (MAX_SEGMENTS,)),  # and voltages, V
        ("seg_vb", f8, (MAX_SEGMENTS,)),
        ("ev", f8, (3, MAX_EVENTS)),  # the switching bridge's events: times, legs, states
        ("no_trace", f8, (0, 3)),  # the bridge's current trace: none
        *CARRY_FIELDS,  # what the bridge carries to the next period and the check
        *NOISE_FIELDS,  # the current sensors' noise, drawn a block of samples ahead
    ]
)

#: The open-loop drive's :class:`Estimate`: no estimator runs.
NO_ESTIMATE = Estimate(0.0, 0j, 0.0, 0.0, 0.0, False, 0.0, 0.0, 0j, 0.0)


# The optional blocks (kernels/features.py): each compiled where its feature is, a stand-in
# returning what the skipped branch leaves elsewhere.


@njit(cache=True, inline="always")
def _r2_tracking_front(pk, cmp, t_cyc, v_use, pc, ctl, Ts):
    """The injection's excitation and the headroom the field weakening leaves it: ``(sine,
    i_inj, v_fw)``."""
    sine, i_inj = excitation(pk, cmp, t_cyc, v_use, 1.0 - ctl.fw_cut, Ts)
    v_fw = v_use
    if pk.inj_amp != 0.0 and pk.inj_fw and cmp.v_peak_last > 0.0:
        # the field weakening leaves the injection headroom
        i_ref = ctl.i_ref_dq  # the speed loop's torque current at its limit
        iq_max = math.sqrt(max(pc.i_max * pc.i_max - i_ref.real * i_ref.real, 0.0))
        lim = abs(i_ref.imag) >= 0.99 * iq_max
        v_fw = headroom_weakening_input(pk, cmp, v_use, lim, 1.0 - ctl.fw_cut)
    return sine, i_inj, v_fw


@njit(cache=True, inline="always")
def _no_r2_tracking_front(pk, cmp, t_cyc, v_use, pc, ctl, Ts):
    return 0.0, 0.0, v_use


@njit(cache=True, inline="always")
def _no_track(pk, cmp, mdl, table, e_dq0, inp, w_r_hat, ti):
    return e_dq0


@njit(cache=True, inline="always")
def _no_r1_standstill(p, m, s, v_alpha, v_beta, i0_a, i0_b, i_a, i_b, w_ref, w_e, Ts):
    return None


@njit(cache=True, inline="always")
def _compensate_inverter(pc, ctl, mdl, smp, smpl, Ts, v_ref_alpha, v_ref_beta, w_ref):
    """The inverter-error compensation the controller adds to its reference and the bridge's
    gate advance: ``(dv_alpha, dv_beta, t_adv)``, V, V, s."""
    i_meas_alpha = smpl.i_meas_ab.real
    i_meas_beta = smpl.i_meas_ab.imag
    dv_alpha, dv_beta = inverter_feedforward(
        pc, ctl, i_meas_alpha, i_meas_beta, Ts, v_ref_alpha, v_ref_beta
    )
    standstill_compensation(ctl, dv_alpha, dv_beta, i_meas_alpha, i_meas_beta, w_ref)
    if mdl.ie_new:  # the standstill test identified the residual: the scale starts there
        start_from_identified(ctl, mdl)
    return dv_alpha, dv_beta, dead_time_advance(pc, ctl, Ts)


@njit(cache=True, inline="always")
def _no_inverter_compensation(pc, ctl, mdl, smp, smpl, Ts, v_ref_alpha, v_ref_beta, w_ref):
    return 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def _no_residual(p, s, m, v_ab, i_prev_ab, i_ab, Ts):
    return None


@njit(cache=True, inline="always")
def _no_inverter_error(pc, ctl, mdl, i_ab):
    return False


@njit(cache=True, inline="always")
def _no_bridge(pinv, sinv, pp, x, v_alpha, v_beta, Vdc_meas, R1b, R2b, TL0, Ts, nsub, ev,
               trace, carry, advance):  # fmt: skip
    return 0.0, 0.0


@njit(cache=True, inline="always")
def _current_offset_only(p, i_s_alpha, i_s_beta, k, buf):
    return i_s_alpha + p.i_offset_ab.real, i_s_beta + p.i_offset_ab.imag


r2_tracking_front = compiled("r2_tracking", _no_r2_tracking_front)(_r2_tracking_front)
track_r2 = compiled("r2_tracking", _no_track)(track)
run_r1_standstill = compiled("standstill_r1", _no_r1_standstill)(r1_standstill)
bridge = compiled("switching_bridge", _no_bridge)(bridge_period)
compensate_inverter = compiled("inverter_compensation", _no_inverter_compensation)(
    _compensate_inverter
)
inverter_residual = compiled("inverter_compensation", _no_residual)(stator_residual)
r1_masked = compiled("inverter_compensation", _no_inverter_error)(r1_masked_by_inverter_error)
current_sensors = compiled("phase_sensors", _current_offset_only)(measure_current_drawn)


@njit(cache=True, inline="always")
def profiles(pp, pt, pv, pn, t, foc, mdl, Ts):
    """The profiles the drive reads at ``t`` (the stages after it read no profile array): the
    references of field-oriented control, or the open-loop voltage. The duty cycle, the speed
    reference's profile and the load's, runs ``mdl.t_hold`` late: the time the standstill R1
    test extended the premagnetisation (``mdl.dc_busy``,
    :func:`imdrive.kernels.r1_standstill.r1_standstill`), so that a load
    step stated after the speed reference's start still comes after it (held alone, the
    reference was overtaken by the load, which hit the drive at standstill)."""
    w_imposed = 0.0
    if pp.speed_imposed:
        w_imposed = profile_at(pt, pv, pn, PR_SPEED_IMPOSED, t)
    R1_base = pp.R1 * profile_at(pt, pv, pn, PR_R1_SCALE, t)
    R2_base = pp.R2 * profile_at(pt, pv, pn, PR_R2_SCALE, t)
    w_ref = 0.0
    psi_ref = 0.0
    v_amp = 0.0
    f_Hz = 0.0
    if foc:
        w_ref = profile_at(pt, pv, pn, PR_SPEED_REF, t - mdl.t_hold)
        if mdl.dc_busy and w_ref != 0.0 and mdl.t_hold < mdl.dc_hold_max:  # the start waits
            mdl.t_hold += Ts
            w_ref = 0.0
        psi_ref = profile_at(pt, pv, pn, PR_FLUX_REF, t)
    else:
        v_amp = profile_at(pt, pv, pn, PR_V_AMP, t)
        f_Hz = profile_at(pt, pv, pn, PR_FREQ, t)
    T_L0 = profile_at(pt, pv, pn, PR_LOAD, t - mdl.t_hold)  # t_hold is 0 in open loop
    return Profiles(w_imposed, R1_base, R2_base, T_L0, w_ref, psi_ref, v_amp, f_Hz)


@njit(cache=True, inline="always")
def measure(feat, pp, psen, x, ctl, prof, t, k, i_next_ab, have_next, scr):
    """The plant's current and the current sensors at ``t``: the :class:`Sample`.

    ``i_next_ab`` is the current :func:`check` computed from this same state after the last
    period (``have_next``), so a saturated machine's curve is solved once a period; the
    sensors' noise comes from the block drawn ahead in the :data:`SCRATCH` record ``scr``.
    """
    if pp.speed_imposed:
        x.w_m = prof.w_imposed
    if have_next:
        i_s_alpha = i_next_ab.real
        i_s_beta = i_next_ab.imag
    else:
        i_s_alpha, i_s_beta = stator_current(pp, x)
    i_meas_alpha, i_meas_beta = current_sensors(feat, psen, i_s_alpha, i_s_beta, k, scr)
    return Sample(
        t, k, complex(i_s_alpha, i_s_beta), complex(i_meas_alpha, i_meas_beta), ctl.theta_e
    )


@njit(cache=True, inline="always")
def r1_test_running(pc, ctl, w_ref):
    """Whether the standstill R1 test is under way: enabled, not done, the speed reference
    at zero (:func:`imdrive.kernels.r1_standstill.r1_standstill`)."""
    return standstill_r1(pc) and ctl.dc_phase < 3.0 and w_ref == 0.0


@njit(cache=True, inline="always")
def estimate(feat, sim, pp, pe, pk, table, x, mdl, ctl, est, cmp, smp, prof, smpl, Vdc_meas, pc):
    """The injection, the selected estimator, the detection and the R2 compensator.

    Returns the :class:`Estimate`; updates the estimator's state ``est`` and the compensator's
    ``cmp`` in place, and the controller's model ``mdl`` where they adapt it.
    """
    t = smpl.t
    Ts = sim.Ts
    # R2 tracking starts in the duty cycle's time, as the profiles run: held back with them
    # while the standstill R1 test extends the premagnetisation (mdl.t_hold, profiles())
    t_cyc = t - mdl.t_hold
    # the modulator's share used, the inverter-error compensation included: the field
    # weakening and the headroom must leave it room (without it, at twice the rated speed on
    # the dead-time bridge the compensation's few percent pushed the sum into the limit)
    v_use = smp.v_use
    sine, i_inj, v_fw = r2_tracking_front(feat, pk, cmp, t_cyc, v_use, pc, ctl, Ts)
    w_ref = prof.w_ref

    # R1 adaptation held from the compensator's start until it first updates and whenever
    # its gating freezes it (transients)
    hold_R1 = pk.enabled and pk.gate and (t_cyc < pk.t_on or cmp.frozen != 0.0)
    # the standstill R1 test runs through this sample if it ran through the last one (it ends
    # after the estimator, at the first sample the speed reference moved)
    testing = r1_test_running(pc, ctl, ctl.w_ref_prev)
    # and, whatever the compensator, while the speed reference moves and the drive settles:
    # the law reads the flux error as a resistance error, and a ramp's is the estimator's lag
    if w_ref != ctl.w_ref_prev:
        ctl.ref_moved_at = t
        ctl.w_ref_prev = w_ref
    hold_R1 = hold_R1 or t - ctl.ref_moved_at < pc.r1_settle
    # and where its drop is below the inverter error the controller compensates
    hold_R1 = hold_R1 or r1_masked(feat, pc, ctl, mdl, smpl.i_meas_ab)
    inp = EstimatorInput(
        smp.v_prev_ab, smp.i_prev_ab, smpl.i_meas_ab, smpl.theta_k, ctl.w_e, ctl.i_ref_dq,
        w_ref, i_inj, hold_R1, Ts, t, ctl.dc_restart,
    )  # fmt: skip
    R2_before = mdl.R2_hat
    w_r_hat, e_dq0 = estimator_step(pe, mdl, est, inp)
    if testing:  # an estimator's own R2 law waits for R1_hat: while the flux builds up it
        mdl.R2_hat = R2_before  # reads the R1 error as an R2 error
    R1_after = mdl.R1_hat
    R2_after = mdl.R2_hat
    if standstill_r1(pc):  # the standstill R1 test, whatever the estimator (after it: the
        i0 = smp.i_prev_ab  # controller's)
        i1 = smpl.i_meas_ab
        v = smp.v_prev_ab
        run_r1_standstill(
            feat, pc, mdl, ctl, v.real, v.imag, i0.real, i0.imag, i1.real, i1.imag, w_ref,
            ctl.w_e, Ts,
        )  # fmt: skip
    if tracks_r2(pk):  # R2 tracking
        # the gate compares torques: iq* at the reference flux, scaled by the field
        # weakening's flux factor (in deep field weakening the speed loop's iq* swings by 1/k
        # more for the same torque, and the gate held R2_hat 80 % of the time at 2 x rated
        # speed), and the speed error weighted by the loop's gain
        ti = TrackingInput(
            t, t_cyc, smpl.k, sine, w_ref, w_r_hat / pp.n_p if sim.sensorless else x.w_m,
            ctl.i_ref_dq.imag * (1.0 - ctl.fw_cut), v_use, ctl.w_e, ctl.w_sl,
            speed_loop_gain(pc, 1.0 - ctl.fw_cut), ctl.i_s_dq.imag, Ts,
        )  # fmt: skip
        e_dq0 = track_r2(feat, pk, cmp, mdl, table, e_dq0, inp, w_r_hat, ti)
    psi_r_ab = estimator_flux(est)
    # an encoder drive's magnetising curve at the estimator's R2-independent flux (its own
    # flux model's is detuned by an R2_hat error there; sensorless, it is not): 0 otherwise
    psi_mag = 0.0 if sim.sensorless else estimator_flux_magnitude(est)
    return Estimate(
        w_r_hat, e_dq0, i_inj, v_use, v_fw, hold_R1, R1_after, R2_after, psi_r_ab, psi_mag
    )


@njit(cache=True, inline="always")
def control(feat, sim, pc, x, mdl, ctl, smp, prof, smpl, estm, foc):
    """Field-oriented control (or the open-loop voltage), dead-time feed-forward, delay.

    Returns the :class:`Command`: the reference of this sample (``v_log_ab``), the one that
    acts this period (``v_ref_ab``: the last sample's with a one-period delay) and the
    dead-time compensation it contains (``dv_ab``).
    """
    t = smpl.t
    Ts = sim.Ts
    w_ref = 0.0
    i_meas_alpha = smpl.i_meas_ab.real
    i_meas_beta = smpl.i_meas_ab.imag
    if foc:
        w_ref = prof.w_ref
        psi_ref = prof.psi_ref
        if mdl.dc_boost != 0.0:  # the standstill test's first current level
            psi_ref *= 1.0 + mdl.dc_boost
        if pc.fw:  # field weakening above base speed (voltage feedback)
            k_max = 1.0
            if pc.fw_bound and ctl.w_e != 0.0 and psi_ref > 0.0:
                M_h, L1_h, _, _ = model_inductances(mdl)
                k_max = pc.fw_v * pc.v_max * M_h / (abs(ctl.w_e) * L1_h * psi_ref)
            psi_ref *= field_weakening(pc, ctl, estm.v_fw, Ts, k_max)
        testing = r1_test_running(pc, ctl, w_ref)
        # excitation for R2 adaptation (Kubota & Matsuse 1994), not while the standstill R1
        # test fits the DC flux build-up
        if sim.flux_inj_amp != 0.0 and not testing:
            psi_ref *= 1.0 + sim.flux_inj_amp * math.sin(2.0 * math.pi * sim.flux_inj_freq * t)
        w_fb = estm.w_r_hat / pc.n_p if sim.sensorless else x.w_m
        if sim.sensorless and testing:
            # the estimate is built on the R1_hat the test is identifying: the speed loop and
            # the frame hold the standstill the reference asks for until it has
            w_fb = w_ref
        if pc.ie_veq and pc.ie_rate > 0.0 and has_feedforward(pc):  # the inverter error
            # left, for the online scale of the compensation (none without it)
            inverter_residual(feat, pc, ctl, mdl, smp.v_prev_ab, smp.i_prev_ab, smpl.i_meas_ab, Ts)
        v_ref_alpha, v_ref_beta = foc_step(
            pc, mdl, ctl, i_meas_alpha, i_meas_beta, w_fb, w_ref, psi_ref, estm.i_inj, Ts,
            estm.psi_r_ab, estm.psi_mag,
        )  # fmt: skip
    else:
        v_ref_alpha, v_ref_beta = open_loop_voltage(ctl, prof.v_amp, prof.f, Ts)

    dv_alpha = 0.0
    dv_beta = 0.0
    t_adv = 0.0
    if has_feedforward(pc):  # inverter-error compensation, on the measured current
        dv_alpha, dv_beta, t_adv = compensate_inverter(
            feat, pc, ctl, mdl, smp, smpl, Ts, v_ref_alpha, v_ref_beta, w_ref
        )
        v_ref_alpha += dv_alpha
        v_ref_beta += dv_beta
    v_log_ab = complex(v_ref_alpha, v_ref_beta)
    if sim.delay > 0:  # the reference of the last sample acts now, this one next period
        held = smp.v_hold_ab
        held_dv = smp.dv_hold_ab
        smp.v_hold_ab = complex(v_ref_alpha, v_ref_beta)
        smp.dv_hold_ab = complex(dv_alpha, dv_beta)
        v_ref_alpha = held.real
        v_ref_beta = held.imag
        dv_alpha = held_dv.real
        dv_beta = held_dv.imag
    v_ref_ab = complex(v_ref_alpha, v_ref_beta)
    return Command(w_ref, v_log_ab, v_ref_ab, complex(dv_alpha, dv_beta), t_adv)


@njit(cache=True, inline="always")
def modulate(pinv, pc, smp, smpl, cmd, switching, Vdc_meas, scr, Ts):
    """The inverter's part at the sample: commanded voltage, average-model segments.

    Returns the :class:`Modulation`: ``v_cmd_ab`` (what the controller commands and believes
    it applies), ``v_app_ab`` (the average model's true period average; for the switching
    bridge the command, replaced by :func:`plant` once the period is integrated) and
    ``n_seg``; fills the segments in the :data:`SCRATCH` record ``scr``; stores the
    commanded voltage less the dead-time compensation and the measured current in ``smp``
    for the next estimator step.
    """
    v_ref_alpha = cmd.v_ref_ab.real
    v_ref_beta = cmd.v_ref_ab.imag
    if switching:
        v_cmd_alpha, v_cmd_beta = limit_magnitude(
            v_ref_alpha, v_ref_beta, Vdc_meas / math.sqrt(3.0)
        )
        v_app_ab = complex(v_cmd_alpha, v_cmd_beta)
        n_seg = 0
    else:
        # the DC-link sensor's gain error scales what the bridge really applies
        k_dc = pinv.Vdc / Vdc_meas
        if k_dc != 1.0:
            v_ref_alpha *= k_dc
            v_ref_beta *= k_dc
        i_s = smpl.i_s_ab
        seg_dt = scr.seg_dt
        seg_va = scr.seg_va
        seg_vb = scr.seg_vb
        n_seg = inverter_segments(
            pinv, v_ref_alpha, v_ref_beta, i_s.real, i_s.imag, Ts, seg_dt, seg_va, seg_vb
        )
        v_app_alpha = 0.0
        v_app_beta = 0.0
        for s in range(n_seg):
            v_app_alpha += seg_dt[s] * seg_va[s]
            v_app_beta += seg_dt[s] * seg_vb[s]
        v_app_ab = complex(v_app_alpha / Ts, v_app_beta / Ts)
        v_cmd_alpha, v_cmd_beta = limit_magnitude(
            v_ref_alpha, v_ref_beta, pinv.Vdc / math.sqrt(3.0)
        )
        v_cmd_alpha = (Ts * v_cmd_alpha) / Ts  # rounded as a one-segment average (bit-identical)
        v_cmd_beta = (Ts * v_cmd_beta) / Ts
        if k_dc != 1.0:
            v_cmd_alpha /= k_dc
            v_cmd_beta /= k_dc
    # the controller knows the voltage it commanded for this period (used by the estimator);
    # the dead-time compensation is not part of it: it is meant to cancel the dead time's
    # loss, so the commanded voltage less the compensation is the controller's best estimate
    # of what reaches the terminals
    if has_feedforward(pc):
        smp.v_prev_ab = complex(v_cmd_alpha - cmd.dv_ab.real, v_cmd_beta - cmd.dv_ab.imag)
    else:
        smp.v_prev_ab = complex(v_cmd_alpha, v_cmd_beta)
    smp.v_use = abs(complex(v_cmd_alpha, v_cmd_beta)) / (Vdc_meas / math.sqrt(3.0))
    smp.i_prev_ab = smpl.i_meas_ab
    return Modulation(complex(v_cmd_alpha, v_cmd_beta), v_app_ab, n_seg, cmd.t_adv)


@njit(cache=True, inline="always")
def log_row(row, pp, pe, x, mdl, ctl, est, cmp, prof, smpl, estm, cmd, v_app_ab):
    """Write one log row: every block's fields at this sample."""
    row.time = smpl.t
    i_s = smpl.i_s_ab
    log_plant(row, pp, x, i_s.real, i_s.imag, prof.T_L0, prof.R1_base, prof.R2_base)
    row.v_alpha = v_app_ab.real
    row.v_beta = v_app_ab.imag
    row.v_ref_alpha = cmd.v_log_ab.real
    row.v_ref_beta = cmd.v_log_ab.imag
    row.i_alpha_meas = smpl.i_meas_ab.real
    row.i_beta_meas = smpl.i_meas_ab.imag
    log_control(row, ctl, cmd.w_ref, smpl.theta_k)
    row.speed_est = estm.w_r_hat / pp.n_p
    row.e_d0 = estm.e_dq0.real
    row.e_q0 = estm.e_dq0.imag
    estimator_log(row, pe, est, pp.n_p)
    row.R2_hat = mdl.R2_hat
    row.R1_hat = mdl.R1_hat
    log_compensator(row, cmp)
    law_log(row, cmp.law)


@njit(cache=True, inline="always")
def plant(feat, pinv, sinv, pp, x, prof, mod, switching, Vdc_meas, nsub, scr, Ts):
    """Integrate the plant over the period: the average model's segments, or the switching
    bridge between its gate events (``scr``: the :data:`SCRATCH` record). Returns the period's
    true average voltage, V (complex)."""
    if switching:
        v_cmd = mod.v_cmd_ab
        v_app_alpha, v_app_beta = bridge(
            feat, pinv, sinv, pp, x, v_cmd.real, v_cmd.imag, Vdc_meas,
            prof.R1_base, prof.R2_base, prof.T_L0, Ts, nsub, scr.ev, scr.no_trace, scr,
            mod.t_adv,
        )  # fmt: skip
        return complex(v_app_alpha, v_app_beta)
    seg_dt = scr.seg_dt
    seg_va = scr.seg_va
    seg_vb = scr.seg_vb
    for s in range(mod.n_seg):
        integrate_segment(
            pp, x, seg_va[s], seg_vb[s], prof.R1_base, prof.R2_base, prof.T_L0, seg_dt[s],
            nsub, None,
        )  # fmt: skip
    return mod.v_app_ab


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
def check(sim, pp, x, smp, mdl, ctl, est, cmp, estm, scr):
    """Divergence after the period: ``(status, i_s_ab)``.

    ``status`` is ``S_OK`` or ``S_NAN``, ``S_CURRENT``, ``S_SPEED``; ``i_s_ab`` the plant's
    current now, A (complex), which the next :func:`measure` takes: the one the switching
    bridge left in the scratch record ``scr`` when it solved the saturated curve there.
    """
    if scr.sat_valid == 1.0:
        i_s_alpha, i_s_beta = scr.sat_i_alpha, scr.sat_i_beta
    else:
        i_s_alpha, i_s_beta = stator_current(pp, x)
    i_s_ab = complex(i_s_alpha, i_s_beta)
    i_mag = math.sqrt(i_s_alpha * i_s_alpha + i_s_beta * i_s_beta)
    if not (math.isfinite(i_mag) and math.isfinite(x.w_m)):
        return S_NAN, i_s_ab
    if not (_controller_finite(smp, mdl, ctl, cmp) and estimator_finite(est)):
        return S_NAN, i_s_ab
    if not math.isfinite(estm.w_r_hat):
        return S_NAN, i_s_ab
    if i_mag > sim.i_lim:
        return S_CURRENT, i_s_ab
    if abs(x.w_m) > sim.w_lim:
        return S_SPEED, i_s_ab
    return S_OK, i_s_ab
