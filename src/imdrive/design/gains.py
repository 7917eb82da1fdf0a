"""Default gains of the current and speed PIs (IFOC) and of Schauder's MRAS, from bandwidths.

Pure Python: the kernels receive the numbers, never these functions.

* current PI, pole-zero cancellation of the stator transient ``sigma L1 di/dt = v - R_sigma i``
  (``R_sigma = R1 + (M/L2)^2 R2``)::

      kp_i = sigma L1 a_c,   ki_i = R_sigma a_c            (closed loop ~ a_c / (s + a_c))

* speed PI, with ``k_t = 1.5 n_p (M/L2) psi*`` the torque constant (N m/A)::

      kp_w = J a_s / k_t,    ki_w = kp_w a_s / 4           (crossover ~ a_s, PI zero at a_s/4)

* MRAS adaptation PI, pole-zero cancellation of the adjustable model's rotor time constant
  (see :func:`default_mras_gains`).
"""

from __future__ import annotations


def torque_constant(n_p: float, M: float, L2: float, psi: float) -> float:
    """The field-oriented torque constant ``k_t = 1.5 n_p (M/L2) psi``, N m/A: the torque per
    ampere of q current at rotor flux ``psi`` (Wb), with ``n_p`` pole pairs and the
    magnetising and rotor inductances ``M``, ``L2`` (H); ``T = k_t i_q`` in the rotor-flux
    frame (Novotny & Lipo, *Vector Control and Dynamics of AC Drives*, Oxford 1996)."""
    return 1.5 * n_p * M / L2 * psi


def default_current_gains(sigma_L1: float, R_sigma: float, bandwidth_rad_s: float):
    """Current PI gains ``(kp, ki)`` in V/A and V/(A s) for closed-loop bandwidth ``a_c``."""
    return sigma_L1 * bandwidth_rad_s, R_sigma * bandwidth_rad_s


def default_speed_gains(J: float, k_t: float, bandwidth_rad_s: float):
    """Speed PI gains ``(kp, ki)`` in A/(rad/s) and A/rad for crossover ``a_s`` (mechanical)."""
    kp = J * bandwidth_rad_s / k_t
    return kp, kp * bandwidth_rad_s / 4.0


def default_mras_gains(
    flux_ref_Wb: float, T2_s: float, bandwidth_rad_s: float
) -> tuple[float, float]:
    """MRAS gains from a bandwidth, by pole-zero cancellation.

    Linearised about a steady state with small slip, the error signal responds to a speed
    error through the adjustable model's rotor time constant::

        e ~ |lam|^2 T2 / (1 + s T2) * (w_r - w_r_hat)

    With the PI ``K1 + K2/s`` and ``K2/K1 = 1/T2`` the PI zero cancels that pole and the loop
    becomes ``K1 |lam|^2 / s``: the estimate follows the true speed with a first-order lag of
    bandwidth ``a = K1 |lam|^2``. Hence::

        K1 = a / |lam|^2,    K2 = K1 / T2

    Parameters
    ----------
    flux_ref_Wb : float
        Rotor-flux magnitude, Wb.
    T2_s : float
        The estimator's rotor time constant L2/R2_hat, s.
    bandwidth_rad_s : float
        Desired bandwidth ``a``, rad/s.

    Returns
    -------
    K1 : float
        Proportional gain, (rad/s)/Wb^2.
    K2 : float
        Integral gain, (rad/s^2)/Wb^2.
    """
    K1 = bandwidth_rad_s / flux_ref_Wb**2
    return K1, K1 / T2_s


#: Corner of the type-2 adaptation's second integrator over the loop's bandwidth, ``b / a``:
#: with ``b = a / 4`` the loop ``a (s + b) / s^2`` has a double closed-loop pole at ``-a/2``
#: (critically damped), as the speed PI's zero at a quarter of its crossover
#: (:func:`default_speed_gains`).
MRAS_TYPE2_CORNER = 0.25


def mras_type2_gains(
    flux_ref_Wb: float, T2_s: float, bandwidth_rad_s: float
) -> tuple[float, float, float]:
    """MRAS gains of the type-2 adaptation ``w_r_hat = u + b \\int u dt``, with ``u`` the PI's
    output ``K1 e + K2 \\int e dt``.

    The PI of :func:`default_mras_gains` cancels the adjustable model's pole and leaves the
    loop ``a / s``: a type-1 tracker, whose estimate lags a constant acceleration ``alpha``
    (electrical rad/s^2) by ``alpha / a``. A second integrator after the PI, with its zero at
    ``b``, ``C(s) = K1 (1 + 1/(s T2)) (1 + b/s)``, makes the loop ``a (s + b) / s^2``: type 2,
    so the estimate follows a constant acceleration with no steady lag (the loop types and
    their steady-state errors under a ramp: Gardner, *Phaselock Techniques*, 3rd ed., Wiley,
    2005, ch. 2; the type-II tracking loop of resolver-to-digital converters is the same
    structure)::

        K1 = a / |lam|^2,   K2 = K1 / T2   (as the type-1 loop),   b = MRAS_TYPE2_CORNER a

    With ``b = a/4`` the closed loop ``a (s + b) / (s + a/2)^2`` is critically damped; the
    error's response to the speed is ``s^2 / (s + a/2)^2``, so when a ramp of acceleration
    ``alpha`` starts the error is ``alpha t exp(-a t / 2)``: at most ``2 alpha / (e a)``
    (0.74 of the type-1 loop's steady lag), at ``t = 2/a``, and below 1 % of that peak after
    ``16 / a`` (0.13 s at 20 Hz). The second integrator in series (rather than a third gain
    on the double integral of ``e``) leaves the PI as it is, so holding the integrator
    leaves the type-1 loop.

    Parameters
    ----------
    flux_ref_Wb : float
        Rotor-flux magnitude, Wb.
    T2_s : float
        The estimator's rotor time constant L2/R2_hat, s.
    bandwidth_rad_s : float
        The loop's crossover ``a``, rad/s.

    Returns
    -------
    K1 : float
        Proportional gain, (rad/s)/Wb^2.
    K2 : float
        Integral gain, (rad/s^2)/Wb^2.
    b : float
        Corner of the second integrator, rad/s.
    """
    K1, K2 = default_mras_gains(flux_ref_Wb, T2_s, bandwidth_rad_s)
    return K1, K2, MRAS_TYPE2_CORNER * bandwidth_rad_s
