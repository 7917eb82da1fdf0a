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
the dot product by ``-lam_hat^2 T2 x d / (1 + x^2)``, so the rotated error's gain to the speed
error is ``cos(phi) - x sin(phi)`` times the unrotated one: an angle of the sign opposite to the
slip's (to the torque's) adds to the loop's gain while its phase moves, and the angle is what
shifts the loop's low-frequency zero out of the right half-plane.

The angle is scheduled (:func:`regeneration_angle`) so that it acts only where it is needed:

    phi = -phi_max sat(i_q* / i_band) r(w_r_hat i_q*) max(0, 1 - |w_e| / w_band)

``r`` is 1 in regeneration (``w_r_hat i_q* <= -w_speed i_band``), 0 in motoring, linear
in between (continuous through zero speed and zero torque); ``w_e`` is the controller's stator
frequency. In motoring and above ``w_band`` the error is Schauder's, bit for bit. The
angle does not make the rotor resistance observable at zero stator frequency: the R2
compensator's own gates keep saying so; what it keeps is the speed loop's stability.
"""

from __future__ import annotations

import math

from numba import njit

from imdrive.kernels.records import f8

#: Fields of ``MRAS_PARAMS`` this module owns (appended to the MRAS's own).
STABILISE_PARAMS = [
    ("phi_max", f8),  # the adaptation error's rotation in the plugging quadrant, rad (0: off)
    ("phi_w_band", f8),  # it ramps in over this much stator frequency, centred on 0, rad/s
    ("phi_w_speed", f8),  # and over this much speed estimate (through zero speed), rad/s
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
    if p.phi_max == 0.0 or abs(lam_old) < 1e-6:
        return 0.0
    turn = lam_new * lam_old.conjugate()
    w_e = math.atan2(turn.imag, turn.real) / Ts
    s_w = min(1.0, max(-1.0, w_r_hat / p.phi_w_speed))
    r = 0.5 - w_e * s_w / p.phi_w_band
    if r <= 0.0:
        return 0.0
    return p.phi_max * s_w * min(r, 1.0)


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
