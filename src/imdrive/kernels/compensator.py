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

Adaptive step law (``p.fine``, this project's)
----------------------------------------------
The published law changes R2_hat by whole multiples of ``G_CR``: with the injection presets'
20 mohm (2.5 % of R2) and the dead zone ``|G_E E| <= 0.25`` the final error is quantised to
about +-0.7 %, and a drifting R2 is followed only once the error has grown into the levels
that give a step as large as the drift per period (a +30 % ramp over 5 s, 24.5 mohm per 0.5 s
period, lagged by 8 %). With ``p.fine`` the update is a second-order tracking loop:

* outside the first threshold (``|x| >= 1``, ``x = G_E E``) the table's level, as published
  (coarse steps, the paper's behaviour for large errors);
* inside it, a continuous level ``CR = fine_gain x`` replaces the table's 0 or +-1: the step
  is proportional to the detected error, so there is no dead zone and no quantisation. At the
  presets' scaling ``x`` was measured at 0.14-0.2 per % of R2 error (150 and 1000 rpm, 3
  and 12 N m), so the default ``fine_gain = 2.5`` moves R2_hat by 0.7-1 times the error per
  whole-period window (half of that per half-period decision, the window below);
* a drift rate ``r`` (ohm per period) integrates the fine steps,
  ``r <- clip(r + drift_gain G_CR CR, +-drift_max)``, and is added to every update:
  ``R2_hat <- R2_hat + G_CR CR + r``. A ramp of R2 (heating) is then followed with zero
  steady lag (a type-2 loop, as a phase-locked loop follows a frequency ramp). It is
  integrated only inside the fine band, so the large initial steps do not wind it up, and it
  is not applied while the gating freezes R2_hat.
* the drift is not integrated *towards* the error while the error shrinks (``x`` and the
  change ``DE`` of the input of opposite signs and ``x`` of the drift's sign): that is the
  proportional step closing an initial error, not a ramp of R2, and integrating it wound the
  drift up by ``drift_gain`` times the whole fine band's travel, which only an equal area of
  overshoot unwound (a type-2 loop's step response; its damping ``~ sqrt(p / drift_gain) / 2``
  falls with the loop's gain per decision ``p``, 0.1-0.3 here). Measured from
  R2_hat(0) = 0.7 R2 on the 2.2 kW Aalto machine at half speed and rated torque: the drift
  reached 1.1 % of R2 per decision at the crossing and R2_hat went on to +2.6 % (before the
  run's end, +2.1 %); without integrating while the error shrinks it approaches from below
  and ends -0.2 %. A ramp still winds the drift up (the error grows until the drift follows
  it), and the drift is always unwound where it pushes against the error; a shrink of less
  than ``p.drift_margin`` of the error per decision is a ramp's lag, not a closing, and a
  drift against a growing error (a ramp that stopped) unwinds ``p.drift_unwind`` times
  faster (:mod:`imdrive.kernels.drift_rate`);
* the fine step keeps its loop gain as R2_hat moves away from ``R2_hat(0)`` (``p.R2_tuned``),
  where ``G_CR`` and the injection frequency were resolved
  (:func:`~imdrive.kernels.sensitivity.fine_loop_gain_ratio`).
* below the stator frequency ``p.drift_fmin`` (period mean, with the gating on; default the
  higher injection frequency, and at least 1.75 times the MRAS filter's corner
  ``wc/2 pi``, above which that filter lags by less than 30 degrees) the drift term is reset
  and not integrated: there the type-2 loop limit-cycled (measured at 50 rpm, 6 N m,
  R2_hat(0) = 0.8 R2: R2_hat swinging +-7 % with a 3 s period, where the type-1 loop
  converges to 0.7 %; at 0.1 x rated speed regenerating at the rated torque from 0.8 R2, a
  swing with a 10 s period at 3.2 Hz on Table IV and Krause 3 hp and at 2.5 Hz on Krause
  50 hp, 1.3 and 1.05 times the corner, above the higher injection frequency of 2.7 and
  1.5 Hz). The speed and slip respond to an R2_hat change through the speed loop and the
  MRAS's filtered voltage model more slowly there, and the second integrator took the phase
  margin. A heating ramp is then followed with a lag, not zero;
* decisions every half compensator period, each on the mean over the last whole period
  (a sliding window of two half-period sums, still whole injection periods): a measurement
  window of 0.5 s alone lets R2 move 3 % (the ramp above) before its error is seen. The
  load gating then compares each half period's mean iq* with the same half one period
  earlier, so the injection's own iq* ripple does not trip it. The drift rate is then per
  half period.

Gating and injection-frequency scheduling (``p.gate``): :mod:`imdrive.kernels.gating`.
"""

from __future__ import annotations

import math

from numba import njit

from imdrive.kernels.compensator_range import thermal_recalibrate
from imdrive.kernels.detection import (  # noqa: F401  (MAX_HP_CORRECTION: old path)
    MAX_HP_CORRECTION,
    compensated_product,
    slip_coupling,
)
from imdrive.kernels.drift_rate import drift_update
from imdrive.kernels.fuzzy import lookup
from imdrive.kernels.gating import (  # noqa: F401  (compensator_gate_sample: old path)
    _gate_decide,
    compensator_gate_sample,
)
from imdrive.kernels.r2_kalman import kalman_decision, kalman_hold
from imdrive.kernels.records import b1, c16, f8, record_dtype
from imdrive.kernels.sensitivity import (  # noqa: F401  (in_phase_sensitivity: old path)
    fine_loop_gain_ratio,
    in_phase_sensitivity,
    injection_sensitivity_ratio,
    saturation_sensitivity_ratio,
)
from imdrive.kernels.step_damping import table_step_factor

#: The quantiser's first threshold on the scaled E (level 1 starts here; Table III's axes).
THRESHOLD_1 = 1.0

#: Parameters of the fuzzy R2 compensator and of the injected sinusoid.
COMPENSATOR_PARAMS = record_dtype(
    [
        ("enabled", b1),  # compensator present
        ("t_on", f8),  # time it is enabled, s
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
        ("inj_lpf", f8),  # optional low-pass on the demodulated product, rad/s (0: none)
        ("inj_t_on", f8),  # time the injection starts, s
        ("gate", b1),  # gating and frequency scheduling on
        ("gate_dw", f8),  # speed-transient threshold, mechanical rad/s
        ("gate_diq", f8),  # load-transient threshold on the period-mean iq*, A
        ("gate_v", f8),  # voltage-saturation threshold, fraction of Vdc/sqrt(3)
        ("gate_df", f8),  # blind band half-width around the injection frequency, Hz
        ("gate_hold", f8),  # decisions skipped after a gating event
        ("inj_freq2", f8),  # the alternative injection frequency, Hz (0: none)
        ("fine", b1),  # adaptive step law: fine level and drift term
        ("fine_gain", f8),  # fine level per unit of scaled E inside the first threshold
        ("drift_gain", f8),  # share of each fine step added to the drift rate
        ("drift_max", f8),  # bound of the drift rate, ohm per compensator period
        ("inj_v_lo", f8),  # injection headroom: voltage use where the amplitude starts to fall
        ("inj_v_hi", f8),  # and where it reaches zero (0: no back-off)
        ("inj_hp_wc", f8),  # MRAS filter cut-off the detection compensates, rad/s (0: plain)
        ("drift_fmin", f8),  # adaptive law: drift integrated only above this |f_e|, Hz (gated)
        ("inj_freq3", f8),  # a third injection frequency for the schedule, Hz (0: two only)
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
        ("damp", b1),  # adaptive law: overshoot damping of the table's steps (step_damping.py)
        ("drift_unwind", f8),  # adaptive law: drift gain's multiple against a growing error
        ("drift_margin", f8),  # and the shrink of the error that counts as closing it
        ("R2_tuned", f8),  # adaptive law: R2_hat its fine gain is tuned at, ohm (0: fixed gain)
        ("kf", b1),  # the Kalman law (r2_kalman.py) instead of the table's levels
        ("kf_r", f8),  # its measurement noise, relative to R2_hat, per decision
        ("kf_q", f8),  # its drift-rate noise, relative to kf_R2, 1/s per sqrt(s)
        ("kf_p0", f8),  # its prior: the relative uncertainty of R2_hat(0)
        ("kf_R2", f8),  # R2_hat(0), ohm
        ("kf_T", f8),  # the decision period, s
        ("det", b1),  # the estimator gives no flux error: the detector's own (flux_detector.py)
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
        ("drift", f8),  # adaptive step law: R2 drift rate, ohm per compensator period
        ("acc_prev", f8),  # adaptive step law: sum of the input over the last half period, Wb
        ("halves", f8),  # half periods in the sliding window since the last reset (0, 1, 2)
        ("g_iq_prev2", f8),  # mean iq* of the half period before the previous one, A
        ("g_iq_known2", b1),  # g_iq_prev2 holds a value
        ("inj_back", f8),  # injection headroom: 1 - the amplitude factor in use
        ("v_peak", f8),  # highest voltage use in the present injection period
        ("g_we", f8),  # sum of the controller's stator frequency over the period, rad/s
        ("fe_mean", f8),  # |stator frequency| over the last decision period, Hz
        ("inj_f_prev", f8),  # frequency in use at the last decision, Hz (three-frequency mode)
        ("v_peak_last", f8),  # peak voltage use over the last whole injection period (0: none)
        ("inj_scale", f8),  # estimation headroom: the amplitude's scale with the flux (0: 1)
        ("g_err_half", f8),  # adaptive step law: speed-error sum of the last half period
        ("g_cnt_half", f8),  # and its samples
        ("live", b1),  # the last decision updated R2_hat from the detected error
        ("th_rise", f8),  # thermal model: rotor temperature above ambient, K
        ("th_R2_cold", f8),  # thermal model: R2 at ambient, calibrated (0: not yet), ohm
        ("th_n", f8),  # thermal model: fine decisions averaged into th_R2_cold so far
        ("inj_running", b1),  # the injection has started
        ("inj_new", b1),  # it started since the last decision (adaptive law: a settling period)
        ("cpl_d", f8),  # the part of e_d0 the slip couples in from e_q0, Wb
        ("cpl_ws", f8),  # the slip command it uses, low-passed over T2_hat, rad/s
        ("damp_n", f8),  # overshoot damping: halvings of the table's steps in force
        ("big_sign", f8),  # and the sign of the last table-level step (0: none yet)
        ("kf_P00", f8),  # Kalman law: its covariance, R2, ohm^2 (0: the prior not yet set)
        ("kf_P01", f8),  # R2 and its rate, ohm^2/s
        ("kf_P11", f8),  # the rate, ohm^2/s^2
        ("dt_lam_i", c16),  # flux detector: current model, Wb (stationary frame)
        ("dt_lam_v", c16),  # its filtered voltage model, Wb
        ("dt_lam_f", c16),  # its filtered current model, Wb
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
    f = s.inj_f if s.inj_f > 0.0 else p.inj_freq
    nxt = ph + 2.0 * math.pi * f * Ts
    s.inj_phase = nxt - 2.0 * math.pi if nxt >= 2.0 * math.pi else nxt
    return math.sin(ph)


@njit(cache=True)
def demodulate(p, s, e_dq0, sine, cosine, w_e, w_s, T2_hat, Ts):
    """Synchronous detection of e_d0 with the injected sinusoid (updates ``s.demod``).

    ``sine``, ``cosine``: ``sin`` and ``cos`` of the injection phase of this sample (both 0
    before the injection starts); ``e_dq0``: the MRAS flux error in the controller's frame,
    Wb; ``w_e``: the controller's stator frequency, electrical rad/s. With ``p.inj_lpf > 0``
    the product is also low-pass filtered (rad/s), for display.

    Plain detection (``p.inj_hp_wc = 0``): ``2 e_d0 sin(phase)``. Filter-compensated detection
    (``p.inj_hp_wc = wc > 0``, :func:`compensated_product`): the MRAS compares the two flux
    models through ``s/(s + wc)`` in the stationary frame, which rotates and scales the
    injection's two side bands at ``w_e +- w_i`` differently when ``|w_e|`` is not far above
    ``wc``; the detection undoes that filter at both side bands.
    """
    f = s.inj_f if s.inj_f > 0.0 else p.inj_freq
    if p.inj_hp_wc > 0.0:
        prod = compensated_product(e_dq0, sine, cosine, w_e, 2.0 * math.pi * f, p.inj_hp_wc)
    else:
        prod = 2.0 * e_dq0.real * sine
    if p.slip_decouple:
        c_d = slip_coupling(s, e_dq0, w_e, p.cpl_wc, w_s, T2_hat, Ts)
        # faded in from cpl_wmin to twice that: below, e_q0 is mostly the voltage model's
        # error (R1, inverter: ~1/w_e), not the rotor's q flux
        k = min(max(abs(w_e) / p.cpl_wmin - 1.0, 0.0), 1.0) if p.cpl_wmin > 0.0 else 1.0
        if k > 0.0:  # (a zero term would turn a -0.0 product into +0.0 in the log)
            prod -= 2.0 * k * c_d * sine
    w_lp = p.inj_lpf
    if w_lp > 0.0:
        s.demod += (1.0 - math.exp(-w_lp * Ts)) * (prod - s.demod)
    else:
        s.demod = prod


@njit(cache=True)
def compensator_update(p, s, m, table, E):
    """One compensator decision from the input ``E`` (Wb); updates ``m.R2_hat`` (MODEL_STATE).

    Returns the output level CR.
    """
    if p.kf:  # the model-based law (r2_kalman.py)
        return kalman_decision(p, s, m, E)
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
    if p.fine and p.demodulated and p.inj_freq > 0.0:
        # the same loop gain at every injection frequency of the schedule
        k = injection_sensitivity_ratio(p, s, m)
        E *= k
        DE *= k
    x = p.G_E * E
    cr = lookup(table, x, p.G_DE * DE)
    dr = p.G_CR * cr
    if p.fine:
        if p.gate and s.fe_mean < p.drift_fmin:
            # low stator frequency: no drift term (a type-1 loop); see the module docstring
            s.drift = 0.0
        if abs(x) < THRESHOLD_1:  # inside the table's first threshold: a continuous level
            cr = p.fine_gain * x * fine_loop_gain_ratio(p, m)
            dr = p.G_CR * cr
            if not (p.gate and s.fe_mean < p.drift_fmin):
                drift_update(p, s, x, p.G_E * DE, dr)
        elif p.damp:
            dr *= table_step_factor(s, cr)
        if abs(x) >= THRESHOLD_1 and x * s.drift < 0.0:
            # a large error against the drift: the drift is wrong (it was not integrated out
            # here and kept walking R2_hat away while the table's level was 0 — measured at
            # 600 rpm, 12 N m, R2_hat(0) = 1.2 R2: -9.5 % after 10 s)
            s.drift = 0.0
        dr += s.drift
    r2 = m.R2_hat + dr
    m.R2_hat = min(max(r2, p.R2_min), p.R2_max)
    s.cr = cr
    s.live = True
    if p.th_on and abs(x) < THRESHOLD_1:
        thermal_recalibrate(p, s, m)
    return cr


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
    if p.fine and n % 2 == 0:
        _compensator_step_sliding(p, s, m, table, k, n, w_e)
        return
    if k % n != 0:
        return
    if p.average and (s.started or p.kf):  # (the Kalman law: always the window's mean)
        E = s.acc / n
    else:
        E = x
    s.acc = 0.0
    if p.gate:
        flags = _gate_decide(p, s, w_e)
        s.frozen = float(flags)
        if flags != 0:
            s.started = False  # no change of E is known across a frozen period
            s.live = False
            if p.kf:
                kalman_hold(p, s, m, p.kf_T)
            return
    compensator_update(p, s, m, table, E)


@njit(cache=True)
def _compensator_step_sliding(p, s, m, table, k, n, w_e):
    """The adaptive step law's decisions: every half period, on the mean of the input over the
    last whole period (two half-period sums), so a drift is seen half a period sooner. A
    decision needs both halves since the start or the last freeze."""
    h = n // 2
    if k % h != 0:
        return
    acc = s.acc
    s.acc = 0.0
    full = s.halves >= 1.0
    E = (s.acc_prev + acc) / n
    s.acc_prev = acc
    s.halves = min(s.halves + 1.0, 2.0)
    if p.gate:
        flags = _gate_decide(p, s, w_e)
        s.frozen = float(flags)
        if flags != 0:
            s.started = False
            s.halves = 0.0  # the window restarts after a frozen half
            s.live = False
            return
    if full:
        compensator_update(p, s, m, table, E)
    else:
        s.live = False


@njit(cache=True)
def log_compensator(row, s):
    """Write this block's :data:`LOG_FIELDS` into the log record ``row``."""
    row.e_d0_demod = s.demod
    row.comp_frozen = s.frozen
    row.inj_freq = s.inj_f
    row.comp_live = 1.0 if s.live else 0.0
    row.rotor_rise = s.th_rise
