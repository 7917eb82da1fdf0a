"""The R2 law's own flux error, for a speed estimator that declares none (the AFO, the EKF).

The injection's R2 signal is the in-phase part of the rotor-flux error between a model that
does not use R2 and one that does (:mod:`imdrive.kernels.r2_kalman`). The MRAS family hands
that error over (its reference and adjustable models, ``e_dq0``); for any other estimator the
detection forms it itself, from the same two models of Schauder's MRAS (C. Schauder, IEEE
Trans. Ind. Appl. 28(5), 1992): the voltage model

    p lam_v = (L2/M) (v - R1_hat i - sigma L1 p i)     (+ the saturating model's terms,
                                                     estimators.common.saturation_increment)

and the current model driven by the running estimator's speed plus a correction

    p lam_i = (-1/T2_hat + j (w_r_hat + dw)) lam_i + (M/T2_hat) i,

both through the low-pass ``1/(s + wc)`` (the MRAS's ``wc``, whose leak of the d error into
q the slip decoupling undoes: :func:`imdrive.kernels.detection.slip_coupling`). Their difference,
turned into the controller's frame (:func:`imdrive.kernels.r2_tracking.track`), is the flux
error ``e_dq0`` the detection demodulates.

**The speed correction.** In the current model a speed error and an R2 error are one and the
same slip error, so the running estimator's own speed error (the AFO's with a wrong R2_hat,
say) reads as an R2 error and the law follows it: on Krause 500 hp at +2 Hz regenerating the
rated torque the AFO's R2_hat ran from 1.2 R2 to the clamp at 3 R2 (and from R2 to +2.8 %,
still climbing). The MRAS cannot have this error: its speed is the one that zeroes the two
models' cross product, and what is left is the R2 signal. So the detector adapts ``dw`` as
Schauder's MRAS adapts its speed (the PI ``det_K1 + det_K2/s`` on the cross product, the
gains this drive's MRAS would have), with the estimator's speed as a feed-forward: R2_hat
then ends -0.14, -0.01 and +0.00 % off from 0.8, 1.0 and 1.2 R2 there. Where that
adaptation is unstable, regenerating at low stator frequency (Harnefors, IEEE Trans. Power
Electron. 15(4), 2000: ``w_r_hat iq* < 0`` and ``|w_e|`` below the rated slip frequency
``det_wmin``), ``dw`` and its integral decay to zero at the filter's rate, back to the
estimator's own speed.

Measured on ``injection-robust-afo`` (the recommended drive on the observer), against the
detector without the correction: the machine envelope (7 machines x 48 runs) 321 converged and
7 lost of 336 against 278 and 14 (4 of the 7 on Krause 2250 hp at rated speed regenerating,
lost by the observer itself without R2 tracking, ``sensorless-afo``); the zero-frequency
study (4 machines, -0.5 ... +2 Hz, 84 runs) 51 converged and 1 lost against 46 and 1. The
hold's alternatives measured: below twice the rated slip, 49 and 1 (envelope 312 and 7);
regeneration told by ``w_e iq* < 0`` instead, which keeps adapting at negative stator
frequencies (plugging), 42 and 3; with that, ``dw`` frozen instead of decayed and twice the
rated slip, 40 and 3 (a frozen correction carries the slip of another load); adapting
everywhere, 38 and 2 (envelope 320 and 7).

**The current's bend over the period.** Both models take the period's mean current as the
MRAS does: the mean of the two samples plus the bend the turning back-emf gives the current
between them (:func:`~imdrive.kernels.estimators.common.period_mean_offset`, 0.15 % of the
current at right angles to the back-emf at twice the rated speed of Table IV). Without it the
detection read a zero error at an R2_hat that depended on the injection's frequency (set from
R2_hat(0)'s rotor corner): at twice the rated speed regenerating the available torque on the
ideal drive (``envelope-full``'s cells, constant R2) R2_hat ended -0.61, -0.09 and +0.11 %
off from 0.7, 1.0 and 1.3 R2, and -1.9 ... +0.27 % over injection frequencies of 0.42-1.69
of the default's; the MRAS's own models, with the bend, 0.00 %. With it the observer drive
ends within 0.004 % on all nine, at +2 and at -2 times the rated speed, and the
MRAS drive with its detection formed here instead of by the MRAS ends as with the MRAS's own
models (to 0.001 %).

The voltage model carries R1_hat, and an R1 error enters the detected error with it; the
estimators that give no flux error do not adapt R1 either (docs/estimators.md). Running the
MRAS's online R1 law on the detector's two models was tried and dropped: 2 of 16 for the AFO,
and the EKF with R1 exact went from 11 to 8 of 16.
"""

from __future__ import annotations

import math

from imdrive.kernels.estimators.common import (
    current_model_step,
    lowpass_coefficients,
    period_mean_offset,
    saturation_increment,
)
from imdrive.kernels.jit import njit
from imdrive.kernels.model import model_inductances


@njit(cache=True)
def window_slip(s):
    """At a decision instant: the window's share of samples with the speed correction off
    (``s.rl_share``) and the current model's mean slip (``s.w_sl_mean``, electrical rad/s);
    restarts the sums."""
    if s.g_dn > 0.0:
        s.rl_share = s.g_rl / s.g_dn
        s.w_sl_mean = s.g_ws / s.g_dn
    s.g_rl = 0.0
    s.g_ws = 0.0
    s.g_dn = 0.0


@njit(cache=True)
def detector_flux_error(p, s, m, inp, w_r_hat):
    """One period of the detector's two flux models (updates ``s.dt_lam_*``): the flux error
    in the stationary frame, Wb (complex; the caller turns it into the controller's).

    Parameters
    ----------
    p, s : COMPENSATOR_PARAMS, COMPENSATOR_STATE records
        ``p.cpl_wc``: the filter's corner, rad/s.
    m : MODEL_STATE record
        The controller's model (``R1_hat``, ``R2_hat``, inductances).
    inp : EstimatorInput
        The period's voltage and current samples, the controller's angle, ``Ts``.
    w_r_hat : float
        The running estimator's speed, electrical rad/s.
    """
    M, _, L2, sigma_L1 = model_inductances(m)
    i0 = inp.i_prev_ab
    i1 = inp.i_ab
    Ts = inp.Ts
    lam_old = s.dt_lam_i
    w_d = w_r_hat + s.dt_w
    i_bend = period_mean_offset(lam_old, w_d, m.R1_hat, m.R2_hat, L2, M, sigma_L1, i0, i1, Ts)
    lam_new = current_model_step(lam_old, w_d, m.R2_hat, L2, M, i0 + i_bend, i1 + i_bend, Ts)
    g, k_in = lowpass_coefficients(p.cpl_wc, Ts)
    i_mean = 0.5 * (i0 + i1) + i_bend
    kv = L2 / M
    d_v = kv * (Ts * (inp.v_ab - m.R1_hat * i_mean) - sigma_L1 * (i1 - i0))
    d_sat = saturation_increment(kv, sigma_L1, s.dt_kv, s.dt_sL, lam_old, i0)
    if d_sat != 0j:  # a saturating model (unsaturated: the same numbers, bit for bit)
        d_v += d_sat
    s.dt_kv = kv
    s.dt_sL = sigma_L1
    s.dt_lam_v = g * s.dt_lam_v + k_in * d_v
    s.dt_lam_f = g * s.dt_lam_f + k_in * (lam_new - lam_old)
    s.dt_lam_i = lam_new
    regen_low = w_r_hat * inp.i_ref_dq.imag < 0.0 and abs(inp.w_e) < p.det_wmin
    if s.on:  # the decision window's sums (window_slip)
        s.g_ws += inp.w_e - w_d
        s.g_dn += 1.0
        if regen_low:
            s.g_rl += 1.0
    if regen_low:  # back to the estimator's speed, at the filter's rate
        k = math.exp(-p.cpl_wc * Ts)
        s.dt_w *= k
        s.dt_int *= k
    elif p.det_K1 > 0.0:  # Schauder's adaptation on the discrepancy
        lv = s.dt_lam_v
        lf = s.dt_lam_f
        e = lv.imag * lf.real - lv.real * lf.imag
        s.dt_int += Ts * e
        s.dt_w = p.det_K1 * e + p.det_K2 * s.dt_int
    return s.dt_lam_v - s.dt_lam_f
