"""Pieces the speed estimators share (the MRAS's adjustable model is :func:`current_model_step`).

The rotor current model in the stationary frame (Park et al., eq. 2)::

    p lam = (-1/T2 + j w_r) lam + (M/T2) i,        T2 = L2/R2

is linear in ``lam`` for a given speed, so it is advanced over one control period exactly, for
a current varying linearly between its two samples (first-order hold), with the complex
exponential of ``z = (-1/T2 + j w_r) Ts`` and the functions ``phi1 = (e^z - 1)/z``,
``phi2 = (e^z - 1 - z)/z^2``.

The two samples miss the current's curvature inside the period (:func:`period_mean_offset`):
the voltage is held over the period while the back-emf turns, so the current bends away
from the chord between its samples by a mean of ``Ts^2 (e' + R1 i')/(12 sigma_L1)``. Its share
of the rotor flux, ``M/sqrt(1 + (w_s T2)^2)`` times that mean, turned the adjustable model by
2.2 mrad at twice the rated speed and full load on Table IV (100 us), and the MRAS read it
as a speed error of 1.9 rpm; second order in the period (0.5 rpm at 50 us).
"""

from __future__ import annotations

import math

from imdrive.kernels.jit import njit


@njit(cache=True)
def period_mean_offset(lam, w_r, R1, R2, L2, M, sigma_L1, i0, i1, Ts):
    """The stator current's mean over the period less the mean of its two samples, A (complex).

    With the voltage held over the period, ``sigma_L1 di/dt = v - R1 i - e`` bends the current
    by the turning back-emf ``e = (M/L2) dlam/dt``: ``i'' = -(R1 i' + e')/sigma_L1``; the mean
    of a curve over ``Ts`` less the mean of its end values is ``-Ts^2 i''/12`` (the
    trapezoidal rule's error), so

        offset = Ts^2 (e' + R1 i') / (12 sigma_L1),
        e' = (M/L2) (z p lam + beta i'),   p lam = z lam + beta i,

    from the rotor current model itself (``z = -R2/L2 + j w_r``, ``beta = M R2/L2``; ``lam``
    at the period's middle, ``i' = (i1 - i0)/Ts``). In steady state ``e' = j w_e e``: at
    twice the rated speed of Table IV and 100 us the offset is 0.15 % of the current, at a
    right angle to the back-emf. Add it to both samples before :func:`current_model_step`
    and to the sample mean of the voltage model's resistive drop.

    Parameters
    ----------
    lam : complex
        Rotor flux of the model at the start of the period, Wb.
    w_r : float
        Electrical rotor speed of the model, rad/s.
    R1, R2 : float
        Stator and rotor resistance of the model, ohm.
    L2, M, sigma_L1 : float
        Rotor, magnetising and stator transient inductance, H.
    i0, i1 : complex
        Stator current at the start and at the end of the period, A.
    Ts : float
        Period, s.
    """
    if not sigma_L1 > 0.0:  # a degenerate model (no leakage left in floating point)
        return 0j
    z = complex(-R2 / L2, w_r)
    beta = M * R2 / L2
    di = (i1 - i0) / Ts
    lam_mid = lam + 0.5 * Ts * (z * lam + beta * i0)
    dlam_mid = z * lam_mid + beta * 0.5 * (i0 + i1)
    e_dot = (M / L2) * (z * dlam_mid + beta * di)
    return Ts * Ts * (e_dot + R1 * di) / (12.0 * sigma_L1)


@njit(cache=True)
def current_model_step(lam, w_r, R2, L2, M, i0, i1, Ts):
    """Rotor flux after one period of the current model, Wb (complex, stationary frame).

    Parameters
    ----------
    lam : complex
        Rotor flux at the start of the period, Wb.
    w_r : float
        Electrical rotor speed, held over the period, rad/s.
    R2, L2, M : float
        Rotor resistance (ohm), rotor and magnetising inductances (H) of the model.
    i0, i1 : complex
        Stator current at the start and at the end of the period, A.
    Ts : float
        Period, s.
    """
    zT = complex(-R2 / L2, w_r) * Ts
    ez = math.exp(zT.real) * complex(math.cos(zT.imag), math.sin(zT.imag))
    if abs(zT) > 1e-4:
        phi1 = (ez - 1.0) / zT
        phi2 = (ez - 1.0 - zT) / (zT * zT)
    else:  # series, avoids cancellation
        phi1 = 1.0 + zT / 2.0 + zT * zT / 6.0
        phi2 = 0.5 + zT / 6.0 + zT * zT / 24.0
    b = M * R2 / L2 * Ts
    return ez * lam + b * (phi1 * i0 + phi2 * (i1 - i0))


@njit(cache=True, inline="always")
def saturation_increment(kv, sigma_L1, kv_prev, sigma_prev, lam, i0):
    """What a saturating model adds to the voltage model's increment over a period, Wb.

    The voltage model's rotor flux is ``lam = (L2/M)(psi_s - sigma L1 i)``; its increment
    ``(L2/M)(Ts (v - R1 i) - sigma L1 di)`` holds while ``L2/M`` and ``sigma L1`` are constant.
    On a saturation-aware model (``[controller_model]``'s magnetising curve) they follow the
    flux, which the R2 injection moves every period, and the increment has two more terms::

        d(L2/M) (psi_s - sigma L1 i) - (L2/M) i d(sigma L1)
            = (d(L2/M) / (L2/M)) lam - (L2/M) i d(sigma L1)

    with ``lam`` the rotor flux (the current model's) and ``i`` the current at the period's
    start, ``i0`` (with them the increment is exact: the difference of ``lam`` at the two
    ends). ``kv``, ``sigma_L1``: this period's ``L2/M`` and ``sigma L1`` (H); ``kv_prev``,
    ``sigma_prev``: the last period's (``kv_prev`` 0: none yet). Exactly 0 on a constant
    model. Measured (saturation alone, R2 injection, 0.2 of the rated speed, regenerating /
    motoring the rated torque): without these terms the observer drive's R̂2 ended +1.4 /
    -0.1 % on Table IV and +2.2 / -0.2 % on the Aalto 2.2 kW machine; with them +0.1 / +0.5 %
    and +0.5 / +0.6 %, a bias that no longer depends on the load
    (tests/kernels/test_saturation_increment.py).
    """
    if kv_prev <= 0.0 or (kv == kv_prev and sigma_L1 == sigma_prev):
        return 0j
    return ((kv - kv_prev) / kv_prev) * lam - kv * (sigma_L1 - sigma_prev) * i0


@njit(cache=True, inline="always")
def lowpass_coefficients(wc, Ts):
    """Pole ``g`` and input gain ``k_in`` of Schauder's low-pass ``1/(s + wc)`` over one
    period of a held input: ``x[k+1] = g x[k] + k_in Ts u[k]``, ``g = exp(-wc Ts)``,
    ``k_in = (1 - g)/(wc Ts)`` (1 at ``wc = 0``, the pure integrator).

    Parameters
    ----------
    wc : float
        Corner, rad/s (>= 0).
    Ts : float
        Period, s.

    Returns
    -------
    (float, float)
        ``g`` and ``k_in``, dimensionless.
    """
    if wc > 0.0:
        g = math.exp(-wc * Ts)
        return g, (1.0 - g) / (wc * Ts)
    return 1.0, 1.0


@njit(cache=True)
def flux_frequency(lam_old, lam_new, Ts):
    """The angular frequency of a flux vector that turned from ``lam_old`` to ``lam_new`` in
    ``Ts`` seconds, rad/s (0 while it is below 1e-6 Wb)."""
    if abs(lam_old) < 1e-6 or abs(lam_new) < 1e-6:
        return 0.0
    turn = lam_new * lam_old.conjugate()
    return math.atan2(turn.imag, turn.real) / Ts


@njit(cache=True, inline="always")
def to_frame(c, x):
    """``e^{-j th} x`` as two floats (real, imaginary), with ``c = (cos th, sin th)``: a
    stationary-frame space vector in the frame at angle ``th`` (the stability maps' reduced
    state, :mod:`imdrive.kernels.linearise`)."""
    return c[0] * x.real + c[1] * x.imag, -c[1] * x.real + c[0] * x.imag
