"""The fuzzy-logic rotor-resistance compensator in the drive (paper §4, Fig. 1), its injection,
detection and gating; with ``p.kf`` the decisions go to the model-based law of
:mod:`imdrive.kernels.r2_kalman` instead of the fuzzy table.

Every compensator period (``p.n`` control periods) after the enable time it forms

    E  = e_d0                      (the MRAS flux error in the rotor-flux frame, Wb)
    DE = E - E_previous            (change per compensator period, Wb)

scales them (``p.G_E``, ``p.G_DE``, 1/Wb: the paper's thresholds are in units of
1e-6, so a gain of 1e6 reproduces them), looks up the output level CR (-6 ... 6) in the 13 x 13
table (the paper's printed Table III or one compiled from rules, :mod:`imdrive.fuzzy`) and
updates

    R2_hat <- clip(R2_hat + G_CR * CR, R2_min, R2_max)

The slip calculation (after the compensator in the same period) and the MRAS (from the next
sample on) read ``R2_hat`` from the controller's model (MODEL_STATE).

Persistent-excitation variant (this project's, not the paper's): a sinusoid of amplitude
``p.inj_amp`` and frequency ``p.inj_freq`` is added to the flux-current reference id*
(:func:`imdrive.control.foc_step`), and the compensator's input becomes the synchronous
detection ``2 e_d0 sin(phase)`` of e_d0 with the injected sinusoid. Averaged over whole
injection periods (the compensator period) it is the in-phase part of the e_d0 oscillation,
which the rotor-time-constant mismatch creates: with the flux responding as
``1/(1 + s T2)`` in the plant and ``1/(1 + s T2_hat)`` in the adjustable model, the in-phase
part of their difference has the sign of ``T2_hat - T2``, i.e. it is negative when
``R2_hat > R2`` — the same sign convention as the paper's e_d0, so the same table applies.
A constant (e.g. discretisation) bias of e_d0 averages out.

By default E is the mean of the input over the compensator period (``p.average``), not a
sample: a boxcar anti-aliasing filter that keeps ripple out of the quantiser.

R2 identification from a low-frequency AC component superimposed on the flux command is the
method of Kubota and Matsuse (H. Kubota, K. Matsuse, "Speed sensorless field-oriented control
of induction motor with rotor resistance adaptation", IEEE Trans. Ind. Appl. 30(5), 1994).
This project's part is feeding its demodulated flux error to the paper's fuzzy table, the
gating below and the measurements.

The adaptive step law of earlier releases (``step_law = "adaptive"``: a fine band, an
integrated drift rate bounded, unwound and reset at low frequency, overshoot damping,
half-period decisions) was removed in 0.2: the model-based law (``p.kf``) gives its step
size, ramp following and damping from one filter (the envelope sweep: 263 of 267 cells within
goal against 259, off the grid 78 of 80 against 80; docs/envelope.md).

Gating and injection-frequency scheduling (``p.gate``): :mod:`imdrive.kernels.gating`.
"""

from __future__ import annotations

import math

from imdrive.kernels.compensator_range import thermal_recalibrate
from imdrive.kernels.detection import slip_coupling
from imdrive.kernels.flux_detector import window_slip
from imdrive.kernels.fuzzy import lookup
from imdrive.kernels.gating import (  # noqa: F401  (compensator_gate_sample: old path)
    _gate_decide,
    compensator_gate_sample,
    injection_frequency_Hz,
)
from imdrive.kernels.jit import njit
from imdrive.kernels.r2_kalman import kalman_decision, kalman_hold, relative_error
from imdrive.kernels.r2_law_registry import (
    NO_LAW_PARAMS,
    NO_LAW_STATE,
    LawWindow,
    law_decide,
    law_hold,
)
from imdrive.kernels.records import b1, c16, f8, record_dtype
from imdrive.kernels.sensitivity import (  # noqa: F401  (in_phase_sensitivity: old path)
    in_phase_sensitivity,
    saturation_sensitivity_ratio,
)

#: The quantiser's first threshold on the scaled E (level 1 starts here; Table III's axes).
THRESHOLD_1 = 1.0

#: Parameters of the fuzzy R2 compensator and of the injected sinusoid.
COMPENSATOR_PARAMS = record_dtype(
    [
        ("enabled", b1),  # compensator present
        ("t_on", f8),  # time it and its injection start in the duty cycle's time, s
        ("n", f8),  # compensator period in control periods
        ("G_E", f8),  # scaling gain of E = e_d0, 1/Wb
        ("G_DE", f8),  # scaling gain of DE = change of E per compensator period, 1/Wb
        ("G_CR", f8),  # resistance change per output level, ohm
        ("R2_min", f8),  # clamp, ohm
        ("R2_max", f8),  # clamp, ohm
        ("demodulated", b1),  # input: e_d0 (paper) or demodulated e_d0 (injection)
        ("average", b1),  # input is the mean over the compensator period, else a sample
        ("inj_amp", f8),  # amplitude of the sinusoid added to id*, A (0: off)
        ("inj_freq", f8),  # its frequency, Hz
        ("inj_t_on", f8),  # time the injection starts in the duty cycle's time, s
        ("gate", b1),  # gating and frequency scheduling on
        ("gate_dw", f8),  # speed-transient threshold, mechanical rad/s
        ("gate_diq", f8),  # load-transient threshold on the period-mean iq*, A
        ("gate_v", f8),  # voltage-saturation threshold, fraction of Vdc/sqrt(3)
        ("gate_df", f8),  # blind band half-width around the injection frequency, Hz
        ("gate_hold", f8),  # decisions skipped after a gating event
        ("inj_freq2", f8),  # the schedule's second harmonic 2 inj_freq, Hz (0: no schedule)
        ("inj_v_lo", f8),  # injection headroom: voltage use where the amplitude starts to fall
        ("inj_v_hi", f8),  # and where it reaches zero (0: no back-off)
        ("inj_freq3", f8),  # and its third, 3 inj_freq, Hz (0: no schedule)
        ("inj_fw", b1),  # estimation headroom: the field weakening leaves the injection room
        ("inj_v_peak", f8),  # peak voltage use per injection period it holds while injecting
        ("inj_fw_rate", f8),  # its (slow) integral gain on that peak, 1/s
        ("fw_v", f8),  # the field weakening's voltage use (control.field_weakening_voltage)
        ("fw_rate", f8),  # and its integral gain, 1/s (control.field_weakening_rate)
        ("th_on", b1),  # rotor thermal model carries R2_hat while it is held
        ("th_tau", f8),  # its thermal time constant, s
        ("th_Rth", f8),  # its thermal resistance, rotor to ambient, K/W
        ("th_alpha", f8),  # temperature coefficient of R2, 1/K
        ("slip_decouple", b1),  # detection: remove the slip's coupling of e_q0 into e_d0
        ("cpl_wc", f8),  # the MRAS filter cut-off that decoupling undoes, rad/s (0: none)
        ("cpl_wmin", f8),  # decoupling from this |w_e| (full at twice it), rad/s (0: always)
        ("sched_wc", f8),  # the schedule keeps both side bands above this corner, rad/s
        ("kf", b1),  # the Kalman law (r2_kalman.py) instead of the table's levels
        ("kf_r", f8),  # its measurement noise, relative to R2_hat, per decision
        ("kf_q", f8),  # its drift-rate noise, relative to kf_R2, 1/s per sqrt(s)
        ("kf_p0", f8),  # its prior: the relative uncertainty of R2_hat(0)
        ("kf_R2", f8),  # R2_hat(0), ohm
        ("kf_T", f8),  # the decision period, s
        ("det", b1),  # the estimator gives no flux error: the detector's own (flux_detector.py)
        ("mean_out", b1),  # the flux error's stationary-frame mean removed (detection.py)
        ("det_K1", f8),  # its speed adaptation's PI, 1/(Wb^2 s) (0: the estimator's speed)
        ("det_K2", f8),  # 1/(Wb^2 s^2)
        ("det_wmin", f8),  # held while regenerating below this |w_e| (rated slip), rad/s
        ("plugin", b1),  # a registered plug-in law decides (r2_law_registry.py; kf_T its period)
        ("law", NO_LAW_PARAMS),  # that law's parameter record (the placeholder's otherwise)
    ]
)

#: State of the compensator.
COMPENSATOR_STATE = record_dtype(
    [
        ("E_prev", f8),  # input at the last compensator sample, Wb
        ("cr", f8),  # last output level
        ("started", b1),  # the first sample has been taken
        ("acc", f8),  # running sum of the input over the current period, Wb
        ("inj_phase", f8),  # phase of the injected sinusoid, rad
        ("demod", f8),  # demodulated (optionally low-pass-filtered) e_d0, Wb
        ("inj_f", f8),  # injection frequency in use, Hz (0: p.inj_freq)
        ("g_flags", f8),  # gating causes seen in the present period (bit mask)
        ("g_wref0", f8),  # speed reference at the start of the period, rad/s
        ("g_err", f8),  # sum of the speed error over the period, rad/s
        ("g_iq", f8),  # sum of iq* over the period, A
        ("g_iq_prev", f8),  # mean iq* of the previous period, A
        ("g_iq_known", b1),  # g_iq_prev holds a value (false before the first period)
        ("g_cnt", f8),  # samples in the sums
        ("g_hold", f8),  # decisions still to skip
        ("frozen", f8),  # why the last decision was skipped (bit mask; 0: updated)
        ("drift", f8),  # Kalman law: R2's drift rate, ohm/s
        ("inj_back", f8),  # injection headroom: 1 - the amplitude factor in use
        ("v_peak", f8),  # highest voltage use in the present injection period
        ("g_rl", f8),  # detector: samples of the window with its speed correction off
        ("g_ws", f8),  # detector: sum of its current model's slip over the window, rad/s
        ("g_dn", f8),  # detector: samples in its window sums
        ("rl_share", f8),  # share of the last window with the speed correction off
        ("w_sl_mean", f8),  # the current model's mean slip over the last window, rad/s
        ("we_mean", f8),  # the controller's mean stator frequency over the last window, rad/s
        ("g_we", f8),  # sum of the controller's stator frequency over the period, rad/s
        ("inj_f_prev", f8),  # frequency in use at the last decision, Hz (three-frequency mode)
        ("v_peak_last", f8),  # peak voltage use over the last whole injection period (0: none)
        ("inj_scale", f8),  # estimation headroom: the amplitude's scale with the flux (0: 1)
        ("live", b1),  # the last decision updated R2_hat from the detected error
        ("th_rise", f8),  # thermal model: rotor temperature above ambient, K
        ("th_R2_cold", f8),  # thermal model: R2 at ambient, calibrated (0: not yet), ohm
        ("th_n", f8),  # thermal model: decisions averaged into th_R2_cold so far
        ("inj_running", b1),  # the injection has started
        ("inj_new", b1),  # it started since the last decision (Kalman law: a settling period)
        ("cpl_d", f8),  # the part of e_d0 the slip couples in from e_q0, Wb
        ("cpl_ws", f8),  # the slip command it uses, low-passed over T2_hat, rad/s
        ("dc_ab", c16),  # the flux error's mean in the stationary frame, Wb
        ("kf_P00", f8),  # Kalman law: its covariance, R2, ohm^2 (0: the prior not yet set)
        ("kf_P01", f8),  # R2 and its rate, ohm^2/s
        ("kf_P11", f8),  # the rate, ohm^2/s^2
        ("dt_lam_i", c16),  # flux detector: current model, Wb (stationary frame)
        ("dt_lam_v", c16),  # its filtered voltage model, Wb
        ("dt_lam_f", c16),  # its filtered current model, Wb
        ("dt_w", f8),  # its speed adaptation: the correction to the estimator's, rad/s
        ("dt_int", f8),  # the adaptation error's integral, Wb^2 s
        ("dt_kv", f8),  # L2/M of the last period (0: none yet)
        ("dt_sL", f8),  # sigma L1 of the last period, H
        ("on", b1),  # the compensator has started (its start in the duty cycle's time)
        ("t_start", f8),  # the run's time it started, s
        ("law", NO_LAW_STATE),  # the plug-in law's state record (the placeholder's otherwise)
    ]
)

#: Log fields of this block.
LOG_FIELDS = (
    "e_d0_demod",  # Wb
    "comp_frozen",  # gating bit mask of the last decision (0: R2_hat updated)
    "inj_freq",  # injection frequency in use, Hz
    "comp_live",  # 1: the last decision estimated R2_hat from the detected error; 0: held
    # (before the compensator's start, frozen by the gating: comp_frozen says why, or its
    # window refilling after a freeze)
    "rotor_rise",  # thermal model: rotor temperature above ambient, K (0 without it)
)


@njit(cache=True)
def injection_sine(p, s, t, Ts):
    """``sin(phase)`` of the injected sinusoid at this sample, 0 before ``p.inj_t_on``.

    Advances the phase held in ``s`` by one period. The injected flux current is
    ``p.inj_amp`` times this value, and :func:`demodulate` detects e_d0 with the same value.
    """
    if t < p.inj_t_on:
        return 0.0
    if not s.inj_running:
        s.inj_running = True
        s.inj_new = True
    ph = s.inj_phase
    f = injection_frequency_Hz(p, s)
    nxt = ph + 2.0 * math.pi * f * Ts
    s.inj_phase = nxt - 2.0 * math.pi if nxt >= 2.0 * math.pi else nxt
    return math.sin(ph)


@njit(cache=True)
def demodulate(p, s, e_dq0, sine, w_e, w_s, T2_hat, Ts):
    """Synchronous detection of e_d0 with the injected sinusoid (updates ``s.demod``).

    ``sine``: ``sin`` of the injection phase of this sample (0 before the injection starts);
    ``e_dq0``: the MRAS flux error in the controller's frame, Wb; ``w_e``: the controller's
    stator frequency, electrical rad/s. The product ``2 e_d0 sin(phase)``, whose mean over whole
    injection periods is e_d0's in-phase part, less the slip's coupling of e_q0
    (:func:`~imdrive.kernels.detection.slip_coupling`). Near DC the MRAS's comparison filter
    ``s/(s + wc)`` turns the side bands ``w_e +- w_i``: the gating's frequency schedule keeps
    them away from it (:mod:`imdrive.kernels.gating`).
    """
    prod = 2.0 * e_dq0.real * sine
    if p.slip_decouple:
        c_d = slip_coupling(s, e_dq0, w_e, p.cpl_wc, w_s, T2_hat, Ts)
        # faded in from cpl_wmin to twice that: below, e_q0 is mostly the voltage model's
        # error (R1, inverter: ~1/w_e), not the rotor's q flux
        k = min(max(abs(w_e) / p.cpl_wmin - 1.0, 0.0), 1.0) if p.cpl_wmin > 0.0 else 1.0
        if k > 0.0:  # (a zero term would turn a -0.0 product into +0.0 in the log)
            prod -= 2.0 * k * c_d * sine
    s.demod = prod


@njit(cache=True)
def compensator_update(p, s, m, table, E):
    """One compensator decision from the input ``E`` (Wb); updates ``m.R2_hat`` (MODEL_STATE).

    Returns the output level CR.
    """
    if p.kf:  # the model-based law (r2_kalman.py)
        return kalman_decision(p, s, m, E)
    if p.plugin:  # a registered law (r2_law_registry.py)
        return plugin_decision(p, s, m, E)
    if not s.started:
        s.started = True
        s.E_prev = E  # no change is known at the first sample
    DE = E - s.E_prev
    s.E_prev = E
    if p.demodulated and m.sat_n > 0:  # the plant's incremental inductance answers
        k = saturation_sensitivity_ratio(p, s, m)
        E *= k
        DE *= k
    if p.inj_fw and s.inj_scale > 0.0:
        # the same loop gain at every flux level: the amplitude follows the flux factor
        E /= max(s.inj_scale, 0.1)
        DE /= max(s.inj_scale, 0.1)
    x = p.G_E * E
    cr = lookup(table, x, p.G_DE * DE)
    dr = p.G_CR * cr
    r2 = m.R2_hat + dr
    m.R2_hat = min(max(r2, p.R2_min), p.R2_max)
    s.cr = cr
    s.live = True
    if p.th_on and abs(x) < THRESHOLD_1:
        thermal_recalibrate(p, s, m)
    return cr


@njit(cache=True)
def plugin_decision(p, s, m, E):
    """A decision of the plug-in law in the compensator's ``law`` slot: the window's detected
    error ``E`` (Wb) and the relative R2 error it measures go to
    :func:`~imdrive.kernels.r2_law_registry.law_decide`; its answer, clamped, becomes
    ``m.R2_hat``. A window that measured R2 within 5 % recalibrates the rotor thermal model
    (``p.th_on``), as with the package's laws. Returns 0 (no table level)."""
    r = relative_error(p, s, m, E)
    w = LawWindow(E, r, p.kf_T, p.R2_min, p.R2_max)
    R2 = law_decide(p.law, s.law, m, w)
    m.R2_hat = min(max(R2, p.R2_min), p.R2_max)
    s.live = True
    if p.th_on and abs(r) < 0.05:
        thermal_recalibrate(p, s, m)
    return 0.0


@njit(cache=True)
def compensator_step(p, s, m, table, e_d0, t, k, w_e=0.0):
    """Called every control period ``k`` at time ``t`` after the MRAS update (``e_d0``, Wb).

    ``w_e``: the controller's synchronous speed, electrical rad/s (the frequency schedule).
    """
    if t < p.t_on:
        return
    n = max(int(p.n), 1)
    x = s.demod if p.demodulated else e_d0  # the input: e_d0 (paper) or demodulated
    s.acc += x
    if k % n != 0:
        return
    if p.average and (s.started or p.kf or p.plugin):  # (a model-based law: always the mean)
        E = s.acc / n
    else:
        E = x
    s.acc = 0.0
    if p.det:  # the window's speed path, for the frequency schedule (gating.py)
        window_slip(s)
    if p.gate:
        flags = _gate_decide(p, s, w_e, m)
        s.frozen = float(flags)
        if flags != 0:
            s.started = False  # no change of E is known across a frozen period
            s.live = False
            if p.kf:
                kalman_hold(p, s, m, p.kf_T)
            elif p.plugin:
                law_hold(p.law, s.law, m, LawWindow(0.0, 0.0, p.kf_T, p.R2_min, p.R2_max))
            return
    compensator_update(p, s, m, table, E)


@njit(cache=True)
def log_compensator(row, s):
    """Write this block's :data:`LOG_FIELDS` into the log record ``row``."""
    row.e_d0_demod = s.demod
    row.comp_frozen = s.frozen
    row.inj_freq = s.inj_f
    row.comp_live = 1.0 if s.live else 0.0
    row.rotor_rise = s.th_rise
