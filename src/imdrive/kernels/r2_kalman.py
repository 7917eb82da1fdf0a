"""A model-based R2 law: a Kalman filter on R2 and its drift rate, fed by the injection's
detected flux error divided by its modelled response (``compensator.step_law = "kalman"``).

The measurement
---------------
The rotor flux answers the injected flux current ``a sin(w_i t)`` through ``L/(1 + s T2)``
(``L``: the magnetising inductance, the incremental one on a saturation-aware model). The
synchronous detection (:func:`imdrive.kernels.compensator.demodulate`), averaged over whole
injection periods, is the in-phase part of the flux error; for ``R2_hat = R2 (1 + r)`` it is,
to first order (:func:`imdrive.kernels.sensitivity.in_phase_sensitivity`)::

    E = -L a S(w_i T2_hat) r,      S(x) = 2 x^2 / (1 + x^2)^2

so each decision window gives a measurement of the relative error, ``r_meas = -E / (L a S)``,
and with it a measurement of R2 itself, ``z = R2_hat / (1 + r_meas)`` (ohm). Measured with
R2_hat held 10 % off (MRAS, injection-robust's drive), the detected E was 0.93-1.07 of this
prediction at half speed and half load and at 0.2 speed and rated load on Table IV and the
Aalto 2.2 kW machine, and 0.59-0.85 at 0.1 speed regenerating at rated torque (where the
MRAS's filtered voltage model lags): a gain below one only slows the filter, it does not
bias it.

Through the detection's filter
------------------------------
An estimator that gives no flux error (the adaptive observer, the EKF) has the detection form
its own through Schauder's two models (:mod:`imdrive.kernels.flux_detector`), compared through
``1/(s + wc)`` in the stationary frame, where the injection's d-axis signal lies in the side
bands ``w_e +- w_i``. Where both lie under the corner (``|w_e| + w_i < wc``: near zero stator
frequency with a slow injection, on the large machines, where no frequency of the schedule
clears its band) the filter differentiates them, and the detection reads a fraction of
``S``: the law divides by the modelled response ``v = Re[G h0]`` there
(:func:`law_response`, :mod:`imdrive.kernels.detection_response`). Krause 500 hp
regenerating the rated torque at +1 Hz (the zero-frequency study): at the 0.19 Hz
injection ``v = 0.15-0.17 S`` (the detection measured 0.03 S with R2_hat pinned,
``studies/detection_gain.py``); dividing by ``S``, R2_hat closed 20 % in over 100 s and the
runs ended at -7.0 and -6.6 %, dividing by ``v`` within 0.25 % (2026-12-01). A window whose
``v`` is not positive measures nothing: it is held as a gated one, with its own gating bit
(:data:`NOT_OBSERVABLE`). The detection's noise reads as ``r`` through ``1/v``, so the
measurement's standard deviation is ``noise_pu S/v``.

Elsewhere the law keeps ``S``, for three reasons measured. With a side band above the
corner the model is no better than ``S``: on Table IV the detection read 0.92-1.06 S where it
gives 0.79-0.96, and dividing by it wherever the detector runs moved `envelope-full`'s
bridge cells at 0.1 of the rated speed with a thermal ramp (``v`` 0.5-0.85 S there): 6 left
the goal, 3 entered it, and that row fell under its 97 %. Where a window ran regenerating
below the rated slip frequency with the detector's speed correction off, its speed path
carries the slip error and the response lies between ``Re[G h0]`` and the slip-coupled
``Re[G h1]``, neither of which the detection follows: on Krause 500 hp at 0.83 Hz the reading
was 7.5 S against 0.9-3.3 S, and dividing by the larger model lost control at +0.5 Hz from
0.8 R2 (R2_hat stepped +25, -36, -25 %). And an estimator that hands its own flux error (the
MRAS family) filters it at a corner that follows the stator frequency and closes its speed
adaptation through it, unmodelled here.

The filter
----------
The state is ``x = [R2, dR2/dt]`` with a constant-velocity model and white acceleration noise
of spectral density ``q = (drift_pu R2_0)^2`` (ohm^2/s^3); the measurement ``z = R2 + v`` with
``std(v) = noise_pu R2_hat``. Per decision period ``T``::

    predict:  x <- F x,  P <- F P F' + q [[T^3/3, T^2/2], [T^2/2, T]],  F = [[1, T], [0, 1]]
    update:   K = P H' / (H P H' + R),  x <- x + K (z - H x),  P <- (I - K H) P,  H = [1, 0]

(Y. Bar-Shalom, X. R. Li, T. Kirubarajan, *Estimation with Applications to Tracking and
Navigation*, Wiley, 2001, §6.3: the white-noise-acceleration model; its steady gains are the
alpha-beta filter's, P. R. Kalata, IEEE Trans. Aerosp. Electron. Syst. 20(2), 1984).

What the fuzzy law's patches did falls out of it: the step size is the gain ``K``, large
while R2 is uncertain and small once the measurements agree (no table levels, no fine band,
no dead zone); the drift rate is the second state (a ramp of R2 is followed with no steady
lag); its damping is the Kalman gain's (no overshoot damping, no drift bound, no unwind
factor); and a window the gating rejects is a missing measurement: the covariance grows and
the next accepted measurement weighs more (R2_hat itself is left where it is, or to the rotor
thermal model). The variance of the measured error ``r`` holds, besides ``noise_pu``, a share
:data:`GAIN_UNCERTAINTY` of ``r`` itself: the linear sensitivity reads a large error only
roughly (0.6-1.9 times, measured). It reaches ``z`` through ``dz/dr = -z/(1 + r)``, so the
measurement's variance is ``(R2_hat/(1 + r)^2)^2 (noise_pu^2 + (GAIN_UNCERTAINTY r)^2)``: a
window that reads R2 far above R2_hat (``r`` near -1, ``z`` many times R2_hat) weighs
little, where the variance of ``r`` alone let one such window on Krause 50 hp near zero
stator frequency (``studies/zero_frequency.py``, +2 Hz from 0.8 R2) take R2_hat from
0.80 R2 to its clamp at 2 R2 in one decision. From R2_hat(0) = 0.7 R2 at half speed and
rated torque R2_hat overshoots by 2.7 % on the Aalto machine and 2.9 % on Krause 50 hp
before it settles within 0.5 % (3.8 and 5.6 % with the variance of ``r`` alone;
tests/drive/test_r2_law_overshoot.py; the adaptive law of earlier releases: under 1 %).
"""

from __future__ import annotations

import math

from imdrive.kernels.compensator_range import thermal_recalibrate
from imdrive.kernels.detection_response import responses
from imdrive.kernels.gating import injection_frequency_Hz
from imdrive.kernels.jit import njit
from imdrive.kernels.model import incremental_L2
from imdrive.kernels.sensitivity import in_phase_sensitivity

#: The relative uncertainty of the detection's gain over its analytic sensitivity: measured
#: 0.59-1.07 with R2_hat 10 % off and about 1.9 from 20 % low at rated load (the detuned
#: orientation moves the operating point), so a measured error ``r`` carries a standard
#: deviation of this share of itself besides ``kf_r``.
GAIN_UNCERTAINTY = 0.6

#: The gating bit of a window whose modelled response is not positive: it does not measure R2
#: (:func:`law_response`; run/status.py names it "not observable").
NOT_OBSERVABLE = 128


@njit(cache=True)
def injection_amplitude(p, s):
    """The injected flux current's amplitude in use, A: the setting scaled by the voltage
    headroom's back-off and the estimation headroom's flux factor."""
    a = p.inj_amp * (1.0 - s.inj_back)
    if p.inj_fw and s.inj_scale > 0.0:
        a *= s.inj_scale
    return a


@njit(cache=True)
def law_response(p, s, m):
    """``(v, S)``: the detection's in-phase response to a relative R2 error the law divides
    by, and the analytic sensitivity ``S``, both per unit of ``L a`` (dimensionless). ``v`` is
    the response through the detector's comparison filter (corner ``p.cpl_wc``) at the
    window's mean stator frequency and slip (``Re[G h0]``,
    :func:`imdrive.kernels.detection_response.responses`), not below 0 (0: the window does
    not measure R2), where both of the injection's side bands lie under the corner; ``S``
    otherwise, where the estimator hands its own flux error, where the window's speed path
    may carry the slip error, and without the gating's window means (module docstring,
    "Through the detection's filter")."""
    f = injection_frequency_Hz(p, s)
    w_i = 2.0 * math.pi * f
    T2 = incremental_L2(m) / m.R2_hat
    S = in_phase_sensitivity(w_i, T2)
    coupled = s.rl_share > 0.5 and abs(s.we_mean) < 2.0 * p.det_wmin  # as gating.py has it
    # both side bands under the filter's corner (module docstring)
    under = abs(s.we_mean) + w_i < p.cpl_wc
    if not (p.det and p.gate and under) or coupled:
        return S, S
    v, _ = responses(w_i, T2, s.w_sl_mean, s.we_mean, p.cpl_wc)
    return max(v, 0.0), S


@njit(cache=True)
def relative_error(p, s, m, E):
    """The relative R2 error ``r = R2_hat/R2 - 1`` one window's detected error ``E`` (Wb)
    measures, ``-E / (L a v)`` (:func:`law_response`); 0 where the window measures none."""
    L = m.L_inc_hat if m.sat_n > 0 else m.M_hat
    v, _ = law_response(p, s, m)
    sens = L * injection_amplitude(p, s) * v
    if sens <= 0.0:
        return 0.0
    return -E / sens


@njit(cache=True)
def kalman_predict(p, s, T):
    """The covariance's prediction over ``T`` seconds (white-noise acceleration)."""
    if s.kf_P00 <= 0.0:  # the prior not yet set
        kalman_start(p, s)
    q = (p.kf_q * p.kf_R2) ** 2
    P00 = s.kf_P00 + 2.0 * T * s.kf_P01 + T * T * s.kf_P11 + q * T**3 / 3.0
    P01 = s.kf_P01 + T * s.kf_P11 + q * T * T / 2.0
    s.kf_P11 += q * T
    s.kf_P00 = P00
    s.kf_P01 = P01


@njit(cache=True)
def kalman_start(p, s):
    """The prior: R2 known to ``kf_p0`` of R2_hat(0), its rate to what ``q`` gives in 10 s."""
    s.kf_P00 = (p.kf_p0 * p.kf_R2) ** 2
    s.kf_P01 = 0.0
    s.kf_P11 = (p.kf_q * p.kf_R2) ** 2 * 10.0
    s.drift = 0.0


@njit(cache=True)
def kalman_hold(p, s, m, T):
    """A decision the gating rejected: no measurement, the covariance grows. R2_hat is left
    where it is (the rotor thermal model carries it while held, if on)."""
    kalman_predict(p, s, T)


@njit(cache=True)
def kalman_update(p, s, m, E, T):
    """One accepted decision window: predict over ``T`` (s), then update with the window's
    detected error ``E`` (Wb). Updates ``m.R2_hat`` (clamped to ``[R2_min, R2_max]``), the
    drift rate ``s.drift`` (ohm/s) and the covariance; returns the relative error measured."""
    kalman_predict(p, s, T)
    v, S = law_response(p, s, m)
    r = relative_error(p, s, m, E)
    r = max(r, -0.9)  # z = R2_hat/(1 + r) stays finite and positive
    R2_pred = m.R2_hat + s.drift * T
    nu = m.R2_hat / (1.0 + r) - R2_pred
    # r's variance carried through z = R2_hat / (1 + r) to first order (dz/dr = -z/(1 + r))
    # the detection's noise reads as r through 1/v: kf_r is its share where v = S
    noise = p.kf_r * (S / v) if v > 0.0 else p.kf_r  # (v = S: exactly kf_r, as before)
    Rv = (m.R2_hat / (1.0 + r) ** 2) ** 2 * (noise**2 + (GAIN_UNCERTAINTY * r) ** 2)
    S = s.kf_P00 + Rv
    K0 = s.kf_P00 / S
    K1 = s.kf_P01 / S
    P01 = s.kf_P01
    s.kf_P11 -= K1 * P01
    s.kf_P01 = (1.0 - K0) * P01
    s.kf_P00 *= 1.0 - K0
    s.drift += K1 * nu
    R2 = R2_pred + K0 * nu
    m.R2_hat = min(max(R2, p.R2_min), p.R2_max)
    return r


@njit(cache=True)
def kalman_decision(p, s, m, E):
    """A decision of the compensator with this law (``p.kf``): :func:`kalman_update` over the
    decision period ``p.kf_T``; a window that measured R2 within 5 % recalibrates the rotor
    thermal model (``p.th_on``). Returns 0 (the table's output level, unused)."""
    v, _ = law_response(p, s, m)
    if v <= 0.0:  # the window does not measure R2: held, as a gated one
        kalman_hold(p, s, m, p.kf_T)
        s.frozen = float(NOT_OBSERVABLE)
        s.live = False
        return 0.0
    r = kalman_update(p, s, m, E, p.kf_T)
    s.live = True
    if p.th_on and abs(r) < 0.05:
        thermal_recalibrate(p, s, m)
    return 0.0
