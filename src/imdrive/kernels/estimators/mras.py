"""Schauder's MRAS speed estimator (paper §2, eqs. 1, 2, 4, 8, 9).

Reference model (voltage model, eq. 1), stationary frame, no speed in it::

    p lam = (L2/M) (v - R1 i - sigma L1 p i)

Adjustable model (current model, eq. 2)::

    p lam_hat = (-1/T2_hat + j w_r_hat) lam_hat + (M/T2_hat) i,    T2_hat = L2/R2_hat

Schauder replaces the reference model's pure integrator ``1/s`` by ``1/(s + wc)`` and passes the
adjustable model's derivative through the same filter, so the two outputs stay comparable; with
``wc = 0`` both are pure integrators. Adaptation (eqs. 4, 8, 9)::

    e = lam_q lam_hat_d - lam_d lam_hat_q,    w_r_hat = K1 e + K2 \\int e dt

(d, q here are the stationary axes alpha, beta). In low-speed regeneration, with the stator
frequency against the speed, ``e`` is read along a rotated direction (:mod:`.mras_stabilise`).

Type-2 adaptation (opt-in ``b2 > 0``; ``mras.acceleration_tracking``): a second integrator after
the PI, ``w_r_hat = u + b2 \\int u dt`` with ``u = K1 e + K2 \\int e dt``. The PI alone, its zero
cancelling the adjustable model's pole, leaves the loop ``a / s`` (``a = K1 |lam|^2``): the
estimate lags a constant acceleration ``alpha`` by ``alpha / a``. The error signal is linear in the
speed error only within about the rotor's corner frequency ``1/T2`` (``e ~ x / (1 + x^2)``, ``x =
T2 (w_r - w_r_hat)`` at small slip), so on a machine with a large ``T2`` this lag leaves the linear
range; and the indirect field orientation, which runs on the estimate, then misplaces its slip by
the lag: measured on Krause's 2250 hp machine (T2 = 1.6 s, ``1/T2`` = 3 rpm) ramping to rated speed
at half the rated torque, a 5.7 rpm lag raised the rotor flux to 2.5 times rated and lost control.
The second integrator removes the steady lag (gains:
:func:`imdrive.design.gains.mras_type2_gains`). It runs only above ``b2_wmin`` of stator frequency,
and once running is held again only below half of it (a hysteresis): near zero stator frequency the
voltage model has little signal and the start-up mode of the estimate rings (docs/stability.md);
there the integral is held, which leaves the type-1 loop with a constant added. Run through the
whole start, the type-2 loop turned that ringing into excursions of the estimate of 955 rpm on the
2250 hp machine starting to 10 % speed (R2_hat = 1.2 R2), and lost control; held below 5 % of the
rated stator frequency (``mras.acceleration_tracking_from_pu``; just above the filter's cut-off
``wc = 15 rad/s``, 0.04 of 60 Hz), 37 rpm and control kept. The threshold must stay below the
stator frequencies the drive holds: at 10 % it sat on the grid's 10 %-speed points, and the speed
dip of a rated-load step there held the integrator while the loop needed it (lost control on Krause
500 hp and 2250 hp, R2_hat = 0.8 R2; held at 5 %, both keep it). Without the hysteresis the same
happened at the grid's 5 %-speed points: switched on and off by every ripple of the stator
frequency there, the loop lost control after a rated-torque step on Krause 500 hp whatever R2_hat
(type 1 alone, or the threshold at 2 or 10 %, held).

The filter's corner at low stator frequency (opt-in ``wc_k > 0``; ``mras.wc_per_stator_frequency``).
Both models pass through ``H(s) = s/(s + wc)``, so in steady state at the stator frequency
``w_e`` the error signal, and with it the adaptation loop's gain ``K1 |lam|^2``, is scaled by
``|H(j w_e)|^2 = w_e^2 / (w_e^2 + wc^2)``: 0.07 at 20 rpm and no load on Table IV
(``w_e`` = 4.2 rad/s, ``wc`` = 15 rad/s), which leaves the 20 Hz estimator a bandwidth of about
1.4 Hz under a 5 Hz speed loop. A rated-load step there then drops the speed through zero
(-13 rpm after 20 ms, the estimate still at 17.6 rpm; with the encoder the dip ends at
-4.5 rpm) into the regenerating low-frequency region where the MRAS is unstable, and control is
lost (envelope-full, 20 rpm, full and half motoring load, even from R2_hat = R2). Below
``wc / wc_k`` the corner follows the stator frequency, ``wc(w_e) = max(wc_min, wc_k |w_e|)``
(capped at ``wc``), so the loop keeps ``1/(1 + wc_k^2)`` of its gain down to
``wc_min / wc_k``: the programmable low-pass filter of Bose & Patel (IEEE Trans. Ind.
Electron. 44(1), 1997), here without their gain and phase correction, which the comparison of
two identically filtered models does not need. In steady state the R1 error's share of the
flux, ``-(L2/M) dR1 i / (j w_e lam)``, does not depend on ``wc``; what a small corner costs is
the slower decay of offsets and start-up transients, and at standstill an R1_hat error leaves
a DC flux error ``(L2/M) dR1 |i| / wc``, hence the floor ``wc_min`` (``mras.wc_min_rad_s``,
5 rad/s: at 3 the standstill R1_hat's dead-time bias on the envelope's bridge, +50 %, put
0.6 Wb into the voltage model as the ramp started and the bridge lost cells at 0.1 x rated
speed; at 7 the 20 rpm load step was lost again). With 0.5 and 5 rad/s the loop keeps 0.41
of its gain at 20 rpm, no load, on Table IV (0.07 with the fixed corner), and the rated-load
step there is held. Above ``wc / wc_k``
(4.8 Hz with 15 rad/s and 0.5) nothing changes: there ``wc`` was chosen for the R1-error
margin at speed (docs/stability.md). ``w_e`` is the adjustable model's own flux frequency
(:func:`flux_frequency`; the stator frequency in steady state) low-passed over ``wc_tau``
(``mras.wc_follow_time_s``, 0.5 s: longer than the R2 compensator's injection period, whose
flux modulation a corner following the raw frequency turned into an R2_hat bias: it doubles
the bias an R1_hat error leaves, at 0.1 x rated speed regenerating the rated torque on Table
IV from 0.7 R2 with R1_hat 1 % low +2.4 % raw, +1.1 % with the low-pass); the corner in use
is ``MRAS_STATE.wc_now``, which the R1 law reads too. The stability maps hold the low-passed
frequency at the operating point's (stability/linear.py).

Discretisation at the control period Ts, with the voltage applied over the last period known
exactly (it was held) and the current taken as the mean of its two end samples:

* reference model increment ``(L2/M) [Ts (v - R1 i_mean) - sigma L1 (i_k - i_{k-1})]``; the
  ``p i`` term integrates exactly to a current difference, so no derivative is ever taken;
* adjustable model: exact solution of the linear 2-D system over Ts for constant w_r_hat and a
  current varying linearly between its samples (complex exponentials);
* the common filter ``1/(s + wc)`` of a derivative constant over the period: exact.

Flux normalisation (opt-in ``psi2_norm > 0``; on with field weakening by default): the
adaptation loop's bandwidth is ``K1 |lam|^2``, so with the flux weakened to 0.3 of its design
value it falls ninefold and the estimate lags an acceleration ninefold more. The error is
then scaled by ``psi_design^2 / |lam_hat|^2`` (the current model's magnitude, floored at a
quarter of the design flux). Measured on a 1000 -> 2500 rpm ramp in 2 s at 6 N m with field
weakening: without it the estimate fell 570 rpm behind and the drive ran away (lost control
at 5.8 s); see docs/stability.md.

Online R1 estimation (opt-in ``k_R1 > 0``; this project's law, in the spirit of the
paper's reference [5], which estimates R1 by an MRAS, and of Kubota et al.'s R1 adaptation,
IEEE Trans. Ind. Appl. 29(2), 1993). An error ``dR1 = R1_hat - R1`` enters only the reference
model: in steady state at the stator frequency ``w_e`` it shifts the filtered voltage-model
flux by ``dlam = -(L2/M) dR1 i / (wc + j w_e)``, whose part in phase with the current is::

    Re(dlam conj(i)) = -(L2/M) |i|^2 dR1 wc / (wc^2 + w_e^2)

The speed adaptation drives the cross product of the two fluxes to zero, not this dot
product, so the dot product ``Re((lam_v - lam_f) conj(i))`` is a signal of R1 alone (an R2
error changes the adjustable model's slip, which the speed estimate absorbs). The law
normalises it by that sensitivity::

    p R1_hat = k_R1 Re((lam_v - lam_f) conj(i)) (wc^2 + w_e^2) / ((L2/M) |i|^2 wc)

so ``p dR1 = -k_R1 dR1`` (a first-order convergence at rate ``k_R1``) wherever the linear
picture holds. The sensitivity falls as ``1/w_e^2``: the law runs only below ``R1_fmax``
and is frozen above it (default 30 Hz, measured on the envelope sweep: at 12 N m a 10 % R1
error still costs 1-2 rpm at 300-600 rpm, so 10 Hz was too low; at 50 Hz the normalised gain,
3000 times the DC one at 33 Hz, turned the flux errors of transients and of the injection into
R1 excursions and R2_hat stayed 3.7 % off at 1000 rpm). With the compensator's gating on, the
law is also held until the compensator starts and whenever the gating freezes it (speed and
load transients; the engine). It is also held in regeneration (``w_e iq* < 0``):
there the speed adaptation's response to the same flux error reverses the loop's sign, and
the envelope sweep measured the drive losing control at 300 rpm, -6 and -12 N m, with the
law running (docs/envelope.md). The current in the dot product is the measured current less
the injected flux-current sinusoid of the R2 compensator (``i_inj`` on the controller's d
axis): the flux error's in-phase response to the injection, times the injected current, has a
mean, which is the R2 compensator's signal, and the R1 law would absorb it. R1 (the DC
part) and R2 (the in-phase part of the AC flux response) are thus separated as in Kubota &
Matsuse (1994). The rate must stay well below the injection's angular frequency: measured at
150 rpm with R2_hat(0) = 1.2 R2, ``k_R1 = 1/s`` left R2_hat 0.8 % off, ``0.3/s`` 0.02 %
(R1_hat within 0.01 % 6 s after the compensator starts, from +-10 %). R1_hat is written to
the controller's model (MODEL_STATE), which the reference model reads from the next sample on.
"""

from __future__ import annotations

import cmath
import math

import numpy as np

from imdrive.kernels.estimators import mras_stabilise as stab
from imdrive.kernels.estimators.common import (  # noqa: F401 (flux_frequency: also from here)
    current_model_step,
    flux_frequency,
    lowpass_coefficients,
    period_mean_offset,
    saturation_increment,
    to_frame,
)
from imdrive.kernels.estimators.registry import ReducedState, register_kernel
from imdrive.kernels.jit import njit
from imdrive.kernels.model import model_inductances
from imdrive.kernels.records import b1, c16, f8, record_dtype

#: Parameters of the MRAS (gains from :func:`imdrive.design.gains.default_mras_gains`).
MRAS_PARAMS = record_dtype(
    [
        ("wc", f8),  # cut-off of the low-pass replacing the integrators, rad/s (0: pure)
        ("K1", f8),  # proportional adaptation gain, (rad/s)/Wb^2
        ("K2", f8),  # integral adaptation gain, (rad/s^2)/Wb^2
        ("b2", f8),  # corner of the type-2 adaptation's second integrator, rad/s (0: type 1)
        ("b2_wmin", f8),  # the second integrator runs above this stator frequency, rad/s
        ("k_R1", f8),  # R1 adaptation rate, 1/s (0: off)
        ("R1_fmax", f8),  # R1 adaptation only below this stator frequency, Hz
        ("R1_min", f8),  # clamps of R1_hat, ohm
        ("R1_max", f8),
        ("psi2_norm", f8),  # flux^2 the gains were designed for, Wb^2 (0: no normalisation)
        ("bend", b1),  # the current model gets the current's mean over the period
        ("wc_k", f8),  # the corner follows wc_k |w_e| below wc (0: fixed at wc)
        ("wc_min", f8),  # and not below this, rad/s
        ("wc_tau", f8),  # time constant of the flux frequency the corner follows, s
    ]
    + stab.STABILISE_PARAMS  # the error's rotation in regeneration
)

#: State of the MRAS.
MRAS_STATE = record_dtype(
    [
        ("lam_v_ab", c16),  # reference (voltage) model rotor flux, filtered, Wb
        ("lam_i_ab", c16),  # adjustable (current) model rotor flux, unfiltered, Wb
        ("lam_f_ab", c16),  # adjustable model passed through the same filter, Wb
        ("int_e", f8),  # integral of the error signal, Wb^2 s
        ("int_w", f8),  # integral of the PI's output (the type-2 adaptation), electrical rad
        ("int_w_run", b1),  # the second integrator runs (above b2_wmin, until below half of it)
        ("w_r_hat", f8),  # speed estimate, electrical rad/s
        ("e_dq0", c16),  # flux error (reference - adjustable) in the controller's frame, Wb
        ("wc_now", f8),  # the filter's corner this period (p.wc_k > 0), rad/s
        ("w_flux", f8),  # the adjustable model's flux frequency, low-passed over p.wc_tau, rad/s
        ("dlam_i_ab", c16),  # adjustable model's change over the last period, Wb
        ("kv", f8),  # the voltage model's L2/M of the last period (0: none yet)
        ("sL", f8),  # and its sigma L1, H
    ]
    + stab.STABILISE_STATE
)

#: Log fields of this block (the engine logs every estimator's ``speed_est``, ``e_d0`` and
#: ``e_q0``; :data:`OWN_LOG_FIELDS` are the MRAS's own).
LOG_FIELDS = (
    "speed_est",  # mechanical rad/s
    "e_d0",  # Wb
    "e_q0",
    "lam_v_alpha",  # reference model, Wb
    "lam_v_beta",
    "lam_i_alpha",  # adjustable model, filtered, Wb
    "lam_i_beta",
    "R1_id_status",  # standstill R1 identification: 0 not run, 1 identified, 2 could not
)


@njit(cache=True)
def mras_step(
    p, m, s, v_prev_alpha, v_prev_beta, i_prev_alpha, i_prev_beta, i_alpha, i_beta, theta_e, Ts
):
    """Advance the MRAS by one control period to the new current sample (updates ``s``).

    Parameters
    ----------
    p : MRAS_PARAMS record
    m : MODEL_STATE record
        The controller's machine model (``R1_hat``, ``R2_hat``, inductances).
    s : MRAS_STATE record
        Updated in place: model fluxes, speed estimate ``w_r_hat`` (electrical rad/s), ``e_dq0``.
    v_prev_alpha, v_prev_beta : float
        Voltage applied over the period that just ended, V.
    i_prev_alpha, i_prev_beta : float
        Measured stator current at the previous sample, A.
    i_alpha, i_beta : float
        Measured stator current at this sample, A.
    theta_e : float
        The controller's field angle at this sample (frame of ``e_dq0``), rad.
    Ts : float
        Control period, s.
    """
    M, L1, L2, sigma_L1 = model_inductances(m)
    R1 = m.R1_hat
    R2 = m.R2_hat

    # the current's mean over the period: its samples' mean plus the bend the turning
    # back-emf gives it (common.period_mean_offset; 1.9 rpm at twice the rated speed)
    i0 = complex(i_prev_alpha, i_prev_beta)
    i1 = complex(i_alpha, i_beta)
    i_bend = 0j
    if p.bend:
        i_bend = period_mean_offset(s.lam_i_ab, s.w_r_hat, R1, R2, L2, M, sigma_L1, i0, i1, Ts)
    i_mean_alpha = 0.5 * (i_alpha + i_prev_alpha) + i_bend.real
    i_mean_beta = 0.5 * (i_beta + i_prev_beta) + i_bend.imag

    # adjustable (current) model, eq. (2): exact over Ts for constant w_hat and a current
    # varying linearly between its two samples (first-order hold) shifted by its bend
    lam_old = s.lam_i_ab
    lam_new = current_model_step(lam_old, s.w_r_hat, R2, L2, M, i0 + i_bend, i1 + i_bend, Ts)
    dlam = lam_new - lam_old

    # the common filter 1/(s + wc) applied to a derivative held over the period; its corner
    # follows the adjustable model's flux frequency at low stator frequency (wc_k > 0)
    wc = p.wc
    if p.wc_k > 0.0:
        a = Ts / max(p.wc_tau, Ts)
        s.w_flux += a * (flux_frequency(lam_old, lam_new, Ts) - s.w_flux)
        wc = filter_corner(p.wc, p.wc_k, p.wc_min, s.w_flux)
        s.wc_now = wc
    g, k_in = lowpass_coefficients(wc, Ts)

    # reference (voltage) model, eq. (1)
    kv = L2 / M
    d_sat = saturation_increment(kv, sigma_L1, s.kv, s.sL, lam_old, i0)
    s.kv = kv
    s.sL = sigma_L1
    d_alpha = kv * (Ts * (v_prev_alpha - R1 * i_mean_alpha) - sigma_L1 * (i_alpha - i_prev_alpha))
    d_beta = kv * (Ts * (v_prev_beta - R1 * i_mean_beta) - sigma_L1 * (i_beta - i_prev_beta))
    if d_sat != 0j:  # a saturating model (unsaturated: the same numbers, bit for bit)
        d_alpha += d_sat.real
        d_beta += d_sat.imag
    lam_v_alpha = g * s.lam_v_ab.real + k_in * d_alpha
    lam_v_beta = g * s.lam_v_ab.imag + k_in * d_beta
    lam_f_alpha = g * s.lam_f_ab.real + k_in * dlam.real
    lam_f_beta = g * s.lam_f_ab.imag + k_in * dlam.imag

    # adaptation, eqs. (4), (8), (9)
    s.phi = stab.regeneration_angle(p, s.w_r_hat, lam_old, lam_new, Ts)
    e = stab.adaptation_error(lam_v_alpha, lam_v_beta, lam_f_alpha, lam_f_beta, s.phi)
    e *= stab.regeneration_gain(p, s.phi, s.w_r_hat, lam_old, lam_new, L2 / R2, Ts)
    if p.psi2_norm > 0.0:
        # the loop's bandwidth K1 |lam|^2 (design.gains) held in field weakening by the current
        # model's own magnitude, unfiltered (the low-speed filter's attenuation stays designed)
        lam2 = lam_new.real * lam_new.real + lam_new.imag * lam_new.imag
        e *= p.psi2_norm / max(lam2, 0.0625 * p.psi2_norm)
    s.int_e += Ts * e
    w_pi = p.K1 * e + p.K2 * s.int_e
    if p.b2 > 0.0:
        # type-2 (design.gains.mras_type2_gains): the PI's output plus b2 times its integral, no
        # lag behind an acceleration; held at low stator frequency (type 1 plus a constant)
        if s.int_w_run:
            s.int_w += Ts * w_pi
        s.w_r_hat = w_pi + p.b2 * s.int_w
    else:
        s.w_r_hat = w_pi

    # flux error (reference minus adjustable) in the controller's synchronous frame
    cs = math.cos(theta_e)
    sn = math.sin(theta_e)
    err_alpha = lam_v_alpha - lam_f_alpha
    err_beta = lam_v_beta - lam_f_beta
    s.e_dq0 = complex(cs * err_alpha + sn * err_beta, -sn * err_alpha + cs * err_beta)

    s.lam_v_ab = complex(lam_v_alpha, lam_v_beta)
    s.lam_i_ab = lam_new
    s.dlam_i_ab = dlam
    s.lam_f_ab = complex(lam_f_alpha, lam_f_beta)


@njit(cache=True)
def log_mras(row, s, n_p):
    """Write this block's :data:`LOG_FIELDS` into the log record ``row``."""
    row.speed_est = s.w_r_hat / n_p
    row.e_d0 = s.e_dq0.real
    row.e_q0 = s.e_dq0.imag
    row.lam_v_alpha = s.lam_v_ab.real
    row.lam_v_beta = s.lam_v_ab.imag
    row.lam_i_alpha = s.lam_f_ab.real
    row.lam_i_beta = s.lam_f_ab.imag


@njit(cache=True)
def mras_r1_step(p, m, s, i_alpha, i_beta, w_e, iq_ref, Ts):
    """Online R1 estimation beside the MRAS (module docstring; updates ``m.R1_hat``).

    ``i_alpha``, ``i_beta``: measured current at this sample less the injected sinusoid, A;
    ``w_e``: the controller's stator frequency, electrical rad/s; ``Ts``: control period, s.
    ``iq_ref``: the controller's torque current, A (R1_hat is held in regeneration,
    ``w_e iq_ref < 0``, and while ``s.phi`` mixes the flux error's dot product into the speed
    adaptation: mras_stabilise). Call after :func:`mras_step`.
    """
    if abs(w_e) > 2.0 * math.pi * p.R1_fmax or w_e * iq_ref < 0.0 or s.phi != 0.0:
        return
    i2 = i_alpha * i_alpha + i_beta * i_beta
    if i2 < 1e-2:
        return
    M, L1, L2, sigma_L1 = model_inductances(m)
    wc = max(s.wc_now if p.wc_k > 0.0 else p.wc, 1.0)
    err = s.lam_v_ab - s.lam_f_ab
    dot = err.real * i_alpha + err.imag * i_beta
    sens = (L2 / M) * i2 * wc / (wc * wc + w_e * w_e)
    r1 = m.R1_hat + Ts * p.k_R1 * dot / sens
    m.R1_hat = min(max(r1, p.R1_min), p.R1_max)


@njit(cache=True)
def filter_corner(wc, wc_k, wc_min, w_e):
    """The filter's corner at the stator frequency ``w_e`` (rad/s): ``wc_k |w_e|``, not below
    ``wc_min`` nor above ``wc`` (module docstring, "The filter's corner at low stator
    frequency"), rad/s."""
    return min(wc, max(wc_min, wc_k * abs(w_e)))


OWN_LOG_FIELDS = LOG_FIELDS[3:]


@njit(cache=True)
def restart_after_test(s):
    """The reference (voltage) model's flux restarts from the adjustable model's through the
    same filter, and the speed adaptation's integrals from zero, as the drive's standstill
    R1 test sets R1_hat (``EstimatorInput.restart``, :mod:`imdrive.kernels.r1_standstill`).
    Integrated through the test with R1_hat(0) and the residual the voltage model
    holds an error of about ``(dR1 |i| + u0)/wc``, which its filter forgets at ``wc`` (5 rad/s
    at standstill with injection-robust's cut-off following the stator frequency): measured
    on the envelope's bridge at 20 rpm from R1_hat(0) = 1.1 R1, the speed estimate then ran
    10 rpm ahead as the ramp began, the rotor went back 29 rpm and stayed at 0 rpm with the
    estimate at the reference (held, R2_hat -25 %). The drive is at standstill, so the
    speed estimate's integral restarts at zero."""
    s.lam_v_ab = s.lam_f_ab
    s.int_e = 0.0
    s.int_w = 0.0


@njit(cache=True, inline="always")
def mras_estimate(p, m, s, inp):
    """The MRAS in the estimator contract (:mod:`imdrive.kernels.estimators.registry`).

    :func:`restart_after_test` where the drive's standstill R1 test has just set R1_hat
    (``inp.restart``), :func:`mras_step`, then the online R1 law (``p.k_R1 > 0``, held while
    ``inp.hold_R1``, on the measured current less the compensator's injected sinusoid).
    Returns the speed estimate of :func:`mras_step` (before the R1 law, which does not change
    it) and the flux error ``e_dq0``.
    """
    v = inp.v_ab
    i0 = inp.i_prev_ab
    i1 = inp.i_ab
    Ts = inp.Ts
    if inp.restart:  # the drive's standstill test set R1_hat at the last sample
        restart_after_test(s)
    # second integrator: on above b2_wmin, held only below half of it (hysteresis: module doc)
    if abs(inp.w_e) >= p.b2_wmin:
        s.int_w_run = True
    elif abs(inp.w_e) < 0.5 * p.b2_wmin:
        s.int_w_run = False
    mras_step(p, m, s, v.real, v.imag, i0.real, i0.imag, i1.real, i1.imag, inp.theta_e, Ts)
    w_hat = s.w_r_hat
    if p.k_R1 > 0.0 and not inp.hold_R1:
        # the injected sinusoid (flux-current axis) taken out of the current
        i_dc_alpha = i1.real - inp.i_inj * math.cos(inp.theta_e)
        i_dc_beta = i1.imag - inp.i_inj * math.sin(inp.theta_e)
        mras_r1_step(p, m, s, i_dc_alpha, i_dc_beta, inp.w_e, inp.i_ref_dq.imag, Ts)
    return w_hat, s.e_dq0


@njit(cache=True)
def log_mras_own(row, p, s, n_p):
    """Write the MRAS's own log fields (the two models' fluxes) into ``row``."""
    row.lam_v_alpha = s.lam_v_ab.real
    row.lam_v_beta = s.lam_v_ab.imag
    row.lam_i_alpha = s.lam_f_ab.real
    row.lam_i_beta = s.lam_f_ab.imag


@njit(cache=True, inline="always")
def mras_finite(s):
    """Whether every state of the MRAS is finite."""
    c = cmath.isfinite
    ok = c(s.lam_v_ab) and c(s.lam_i_ab) and c(s.lam_f_ab) and math.isfinite(s.int_e + s.int_w)
    return ok and math.isfinite(s.w_r_hat) and c(s.e_dq0)


# --- the MRAS's states in the stability maps' reduced drive state (kernels/linearise.py) -----

#: Names and typical magnitudes of the MRAS's states in the reduced state (controller's frame).
REDUCED_NAMES = (
    "lam_v_d", "lam_v_q", "lam_i_d", "lam_i_q", "lam_f_d", "lam_f_q", "int_e", "w_r_hat",
    "int_w2",
)  # fmt: skip
REDUCED_SCALE = (0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 1e-4, 1.0, 1.0)


@njit(cache=True)
def mras_reduce(p, s, c, z, k):
    """The MRAS's states into ``z[k:k + 9]`` (``ReducedState.reduce``). The type-2 second
    integrator is a state where it runs; where it is held (below ``b2_wmin`` of stator
    frequency) its value is a constant offset of the estimate that does not change the
    small-signal model, so it is held at 0 (an eigenvalue 0, not the neutral 1 of a value
    that never moves)."""
    z[k], z[k + 1] = to_frame(c, s.lam_v_ab)
    z[k + 2], z[k + 3] = to_frame(c, s.lam_i_ab)
    z[k + 4], z[k + 5] = to_frame(c, s.lam_f_ab)
    z[k + 6] = s.int_e
    z[k + 7] = s.w_r_hat
    z[k + 8] = s.int_w if s.int_w_run and p.b2 > 0.0 else 0.0


@njit(cache=True)
def mras_restore(z, k, s):
    """``z[k:k + 9]`` back into the MRAS's state (``ReducedState.restore``)."""
    s.lam_v_ab = complex(z[k], z[k + 1])
    s.lam_i_ab = complex(z[k + 2], z[k + 3])
    s.lam_f_ab = complex(z[k + 4], z[k + 5])
    s.int_e = z[k + 6]
    s.w_r_hat = z[k + 7]
    s.int_w = z[k + 8]


def second_integrator_runs(p, w_e):
    """Where the type-2 MRAS's second integrator runs at the stator frequency ``w_e`` (rad/s):
    ``b2 > 0`` and ``|w_e| >= b2_wmin`` of parameter record ``p`` (:func:`mras_estimate`; its
    hysteresis below is the held state's, which the steady state does not reach from above)."""
    return (p["b2"] > 0.0) & (np.abs(w_e) >= p["b2_wmin"])


def mras_steady(c, p, I, w_e, w_r_hat):
    """The MRAS's states in the continuous steady state (``ReducedState.steady``).

    The adjustable model at the estimate, ``lam_i = M_hat I / (1 + j (w_e - w_r_hat) T2_hat)``;
    both models through the filter ``j w_e / (j w_e + wc)`` at the corner in effect there; the
    reference model from the stator voltage ``v = R1 I + j w_e psi_s`` (``c["v"]``); the PI's
    integral ``w_r_hat / K2`` (type 1), or the second integrator ``w_r_hat / b2`` with the PI's
    output 0 where it runs (type 2).
    """
    n = len(I)
    z = np.zeros((n, len(REDUCED_NAMES)))
    T2h = c["L2_hat"] / c["R2_hat"]
    lam_i = c["M_hat"] * I / (1.0 + 1j * (w_e - w_r_hat) * T2h)
    wc = np.full(n, float(p["wc"]))
    if p["wc_k"] > 0:  # the corner following the stator frequency (module docstring)
        wc = np.minimum(p["wc"], np.maximum(p["wc_min"], p["wc_k"] * np.abs(w_e)))
    filt = 1j * w_e / (1j * w_e + wc) if p["wc"] > 0 else np.ones(n)
    den = 1j * w_e + wc
    den = np.where(np.abs(den) < 1e-9, 1e-9, den)
    emf = (c["v"] - c["R1_hat"] * I) - 1j * w_e * c["sL1_hat"] * I
    lam_v = (c["L2_hat"] / c["M_hat"]) * emf / den
    for j, val in enumerate((lam_v, lam_i, lam_i * filt)):
        z[:, 2 * j] = val.real
        z[:, 2 * j + 1] = val.imag
    w_r_hat = np.broadcast_to(w_r_hat, (n,))
    z[:, 6] = w_r_hat / p["K2"] if p["K2"] != 0 else 0.0
    z[:, 7] = w_r_hat
    run = np.broadcast_to(second_integrator_runs(p, w_e), (n,))
    z[run, 6] = 0.0
    z[run, 8] = w_r_hat[run] / max(float(p["b2"]), 1e-300)
    return z


@njit(cache=True)
def mras_flux_magnitude(s):
    """The adjustable model's rotor-flux magnitude, Wb: the machine's whatever R̂2, once the
    speed adaptation has turned the model onto the voltage model's angle (the registry's
    ``flux_magnitude``; an encoder drive's magnetising curve reads it)."""
    return abs(s.lam_i_ab)


KERNEL = register_kernel(
    "mras",
    MRAS_PARAMS,
    MRAS_STATE,
    mras_estimate,
    log_fields=OWN_LOG_FIELDS,
    log=log_mras_own,
    finite=mras_finite,
    reduced=ReducedState(
        REDUCED_NAMES, REDUCED_SCALE, mras_reduce, mras_restore, mras_steady, "w_r_hat"
    ),
    flux_magnitude=mras_flux_magnitude,
)
