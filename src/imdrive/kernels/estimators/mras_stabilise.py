"""The MRAS's rotated adaptation error in low-speed regeneration (``mras.regeneration_angle``).

Schauder's adaptation reads the cross product of the two models' fluxes,
``e = Im{lam_v conj(lam_f)}`` (:mod:`imdrive.kernels.estimators.mras`). Near zero stator
frequency while the rotor turns against the torque (regeneration at low speed) the closed
loop of that estimator, the indirect field orientation that runs on its estimate and the speed
controller has a pole in the right half-plane: the well-known instability of the MRAS and
speed-adaptive observer family there (Harnefors, IEEE Trans. Power Electron. 15(4), 2000;
Harnefors & Hinkkanen, IEEE J. Emerg. Sel. Topics Power Electron. 2(2), 2014). The remedy
used here is theirs for the speed-adaptive observer (Hinkkanen & Luomi, IEEE Trans. Ind.
Electron. 51(6), 2004), carried over to the MRAS: the error is read along a rotated direction,

    e = Im{(lam_v - lam_f) conj(lam_f) e^{-j phi}}
      = cos(phi) Im{lam_v conj(lam_f)} - sin(phi) Re{(lam_v - lam_f) conj(lam_f)}

(the error vector ``lam_v - lam_f`` is rotated: ``Im{lam_f conj(lam_f)} = 0`` leaves the cross
product as it is, and ``Re{(lam_v - lam_f) conj(lam_f)}``, the flux magnitude mismatch, zero
where the models agree, is added to it; rotating ``lam_v`` itself would add ``|lam_f|^2`` and
move the equilibrium). A speed error ``d`` misplaces
the rotor's slip by ``d``; in steady state (rotor flux ``lam_hat``, slip ``w_sl`` of the
controller, ``x = w_sl T2``) it moves the cross product by ``-lam_hat^2 T2 d / (1 + x^2)`` and
the dot product by ``-lam_hat^2 T2 x d / (1 + x^2)`` (both times the filter's ``|H(j w_e)|^2``),
so the rotated error's steady gain to the speed error is ``cos(phi) - x sin(phi)`` times the
unrotated one: an angle of the sign opposite to the slip's (to the torque's) adds to it. What
the angle does to the loop's dynamics was measured on the linearised drive (below).

The angle is scheduled (:func:`regeneration_angle`) on the adjustable model's flux frequency
``w_e`` (the stator frequency in steady state) and the speed estimate::

    phi = phi_max s r,    s = sat(w_r_hat / w_speed),    r = clip(1/2 - w_e s / w_band, 0, 1)

full where the stator frequency is against the speed (the *plugging* quadrant: regeneration
below the slip speed, where the slip is larger than the speed and of the other sign), none where
it is ``w_band / 2`` or more with the speed, and continuous through zero speed. Its sign is the
speed's, opposite to the torque's there, which adds to the loop's steady gain. Measured on the
linearised drive (:mod:`imdrive.stability.linear`; ``sensorless``, Table IV, R2_hat = R2, 20 rpm
regenerating half the rated torque, stator frequency -0.7 Hz): least stable pole +3.8 +- 6.7j /s
without, -3.5 /s with 80 deg; at 5 % of the rated speed regenerating the rated torque from
R2_hat = 1.3 R2, +12.0 /s (real) without, -1.0 /s with. The angle was scanned (with a wider
ramp): 30 / 60 / 85 deg gave -0.1 / -2.1 / -3.3 /s at the first point, and 80 deg is Hinkkanen
and Luomi's ``0.44 pi``. Applied with the stator frequency *with* the speed (regeneration above
the slip speed, where the plain MRAS is stable) it destabilised the loop (+16 /s at 5 % speed,
rated regenerating torque, R2_hat = R2, stator frequency +0.22 Hz), hence the narrow ramp
(``mras.regeneration_band_pu``, 0.005: 0.3 Hz on Table IV). Left: within about +-0.1 Hz of zero
stator frequency at high regenerating torque a weakly unstable mode remains (+0.1 ... +1.7 /s on
Table IV at the rated torque), where the voltage model has no signal at all.

The angle also ramps in with the adjustable model's flux magnitude, from ``phi_lam_on`` to
``phi_lam_full`` (0.6 and 0.9 of the flux reference,
:data:`imdrive.config.mras_regeneration.FLUX_BUILT`): while the flux builds up the models'
magnitudes differ by the build-up, and the dot product fed that back into the speed estimate,
whose sign sets the angle's (at standstill with current-sensor offsets and noise the estimate
ran to 16 rpm on Table IV and 222 rpm on the Aalto 2.2 kW machine, the rotor to 5 and 76 rpm).

The rotated error's steady gain falls with the slip as ``(cos phi - x sin phi)/(1 + x^2)`` of
the unloaded cross product's, ``x = w_sl T2``; at the rated regenerating torque ``x`` is 1.45 on
Table IV and 3.1 on Krause's 50 hp machine, where the gain is 0.52 and 0.30 of it and the MRAS's
loop (20 Hz designed) is barely faster than the 5 Hz speed loop. Measured on the linearised
``sensorless`` drive at 5 % of the rated speed regenerating the rated torque, stator frequency
-0.36 Hz (full angle): from R2_hat = 1.2 R2 the least stable pole is +1.33 +- 5.7j /s on Krause
50 hp (+0.55 from 1.3 R2) and +0.63 +- 4.4j /s on Table IV; no angle from 30 to 85 deg makes
it stable on Krause 50 hp (+0.98 at 85 deg). ``mras.regeneration_gain`` (``p.phi_gain``,
:func:`regeneration_gain`) scales the error back to the unloaded gain at the adjustable model's
slip, blended in with the angle: the pole moves to -0.32 /s (-0.89 from 1.3 R2) and -0.46 /s
on Table IV. It is off by default: in simulation the rated regenerating step at 5 % speed
still ends in a flux collapse and a runaway on Krause 50 hp from 1.2 R2 (a second after the
limit cycle has died down, so a large-signal basin, not the linear loop), and Krause 3 hp
(``sensorless``, 1.2 R2) and the Aalto machine (``injection-robust``, 1.2 R2) each lost a
cell of the machine envelope there that they hold without it; from 1.3 R2 Krause 50 hp held.

While the angle acts the online R1 law is held (``mras_r1_step``): its premise, that the speed
adaptation drives the cross product to zero and leaves the dot product to R1, no longer holds
(measured: both running, the speed drifted 43 rpm off in 30 s at 20 rpm regenerating the
rated torque; R1 held, 0.2 rpm). The angle does not make the rotor resistance observable at
zero stator frequency: the R2 compensator's own gates keep saying so; what it keeps is the
speed loop's stability.
"""

from __future__ import annotations

import math

from imdrive.kernels.estimators.common import flux_frequency
from imdrive.kernels.jit import njit
from imdrive.kernels.records import f8

#: Fields of ``MRAS_PARAMS`` this module owns (appended to the MRAS's own).
STABILISE_PARAMS = [
    ("phi_max", f8),  # the adaptation error's rotation in the plugging quadrant, rad (0: off)
    ("phi_w_band", f8),  # it ramps in over this much stator frequency, centred on 0, rad/s
    ("phi_w_speed", f8),  # and over this much speed estimate (through zero speed), rad/s
    ("phi_lam_on", f8),  # none while the adjustable model's flux is below this, Wb
    ("phi_lam_full", f8),  # full from this flux up (linear between), Wb
    ("phi_gain", f8),  # how much of the loop gain lost to the slip the rotated error restores
]

#: Fields of ``MRAS_STATE`` this module owns.
STABILISE_STATE = [
    ("phi", f8),  # the adaptation error's rotation this period, rad
]


@njit(cache=True)
def regeneration_angle(p, w_r_hat, lam_old, lam_new, Ts):
    """The adaptation error's rotation (module docstring), rad.

    Parameters
    ----------
    p : MRAS_PARAMS record
        ``phi_max`` (rad), ``phi_w_band`` (rad/s), ``phi_w_speed`` (rad/s).
    w_r_hat : float
        Speed estimate, electrical rad/s.
    lam_old, lam_new : complex
        The adjustable model's rotor flux at the last sample and now, stationary frame, Wb:
        its turn over the period is the stator frequency ``w_e`` the angle is scheduled on (in
        steady state the controller's; a function of the estimator's own state, so the
        linearised loop sees it).
    Ts : float
        Control period, s.

    Returns
    -------
    float
        ``phi``, rad, of the speed estimate's sign: 0 where the stator frequency is
        ``phi_w_band / 2`` or more of the speed's sign, and while ``phi_max`` is 0.
    """
    lam = abs(lam_new)
    if p.phi_max == 0.0 or abs(lam_old) < 1e-6 or lam <= p.phi_lam_on:
        return 0.0
    # while the flux builds up the two models' magnitudes disagree by the build-up itself,
    # not by a speed error: the dot product would feed it back into the speed estimate
    span = p.phi_lam_full - p.phi_lam_on
    k_lam = min(1.0, (lam - p.phi_lam_on) / span) if span > 0.0 else 1.0
    w_e = flux_frequency(lam_old, lam_new, Ts)
    s_w = min(1.0, max(-1.0, w_r_hat / p.phi_w_speed))
    r = 0.5 - w_e * s_w / p.phi_w_band
    if r <= 0.0:
        return 0.0
    return p.phi_max * s_w * min(r, 1.0) * k_lam


@njit(cache=True)
def adaptation_error(lam_v_alpha, lam_v_beta, lam_f_alpha, lam_f_beta, phi):
    """``Im{(lam_v - lam_f) conj(lam_f) e^{-j phi}}``, Wb^2: Schauder's cross product (eq. 9
    of the paper) read along the direction ``phi`` (rad); at ``phi = 0`` exactly the cross
    product. The error vector ``lam_v - lam_f`` (not ``lam_v``) is rotated, so the dot product
    it adds is the magnitude mismatch, zero where the two models agree."""
    cross = lam_v_beta * lam_f_alpha - lam_v_alpha * lam_f_beta
    if phi == 0.0:
        return cross
    d_alpha = lam_v_alpha - lam_f_alpha
    d_beta = lam_v_beta - lam_f_beta
    dot = d_alpha * lam_f_alpha + d_beta * lam_f_beta
    return math.cos(phi) * cross - math.sin(phi) * dot


@njit(cache=True)
def regeneration_gain(p, phi, w_r_hat, lam_old, lam_new, T2_hat, Ts):
    """The factor that gives the rotated error the steady loop gain of the unloaded MRAS
    (``p.phi_gain = 1``; 0: none, the default).

    At the slip ``x = w_sl T2_hat`` (``w_sl = w_e - w_r_hat``, the adjustable model's slip)
    the rotated error's steady gain to a speed error is ``(cos phi - x sin phi)/(1 + x^2)``
    times the unloaded cross product's (module docstring). The factor is its inverse, blended
    in with the angle, ``1 + p.phi_gain (phi/phi_max) ((1 + x^2)/(cos phi - x sin phi) - 1)``:
    1 wherever the angle is 0 (Schauder's error and its gains as designed).

    Parameters
    ----------
    p : MRAS_PARAMS record
        ``phi_max`` (rad), ``phi_gain`` (0 to 1).
    phi : float
        This period's rotation (:func:`regeneration_angle`), rad.
    w_r_hat : float
        Speed estimate, electrical rad/s.
    lam_old, lam_new : complex
        The adjustable model's rotor flux at the last sample and now, stationary frame, Wb.
    T2_hat : float
        The model's rotor time constant ``L2_hat/R2_hat``, s.
    Ts : float
        Control period, s.

    Returns
    -------
    float
        The factor, dimensionless, >= 1.
    """
    if phi == 0.0 or p.phi_gain == 0.0:
        return 1.0
    x = (flux_frequency(lam_old, lam_new, Ts) - w_r_hat) * T2_hat
    g = math.cos(phi) - x * math.sin(phi)
    k_full = (1.0 + x * x) / max(g, math.cos(phi))
    return 1.0 + p.phi_gain * abs(phi / p.phi_max) * (k_full - 1.0)
