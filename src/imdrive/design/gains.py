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
