"""Default parameters of the alternative speed estimators, and the AFO's linearised analysis.

Pure Python/numpy: the kernels receive the numbers, never these functions. Notation: ``k =
M/L2``, ``sigma L1 = L1 - M^2/L2``, ``R_sigma = R1 + k^2 R2``, ``T2 = L2/R2``, ``psi`` the rotor
flux magnitude (Wb), ``a`` a bandwidth (rad/s).

* Reactive-power MRAS (Peng & Fukao 1994, :mod:`imdrive.kernels.estimators.reactive_mras`):
  see :func:`default_reactive_mras_gains`.
* Adaptive full-order observer (Kubota et al. 1993, :mod:`imdrive.kernels.estimators.afo`):
  :func:`default_afo_gains`, :func:`afo_dc_sensitivity`, :func:`afo_linearised`.
* EKF (:mod:`imdrive.kernels.estimators.ekf`): :func:`default_ekf_noise`.
"""

from __future__ import annotations

import numpy as np


def default_reactive_mras_gains(psi: float, L2: float, bandwidth_rad_s: float, kappa=0.3):
    """Reactive-power MRAS gains ``(K1, K2)``, (rad/s)/(A V) and (rad/s^2)/(A V).

    A step of the speed estimate turns the adjustable model's flux derivative at once
    (``p lam_hat = j w_r_hat lam_hat + ...``), so ``q_hat`` moves by ``G d(w_r_hat)`` with the
    high-frequency sensitivity ``G = (M/L2) psi i_d = psi^2/L2`` (flux frame, ``i_d = psi/M``).
    With the PI ``K1 + K2/s`` acting on ``q - q_hat`` the estimate then follows with the pole
    ``s = -K2 G/(1 + K1 G)``; hence, for bandwidth ``a`` and a proportional share ``kappa =
    K1 G`` (kept below 1: the proportional path acts through a one-period delay)::

        K1 = kappa / G,          K2 = a (1 + kappa) / G

    At low frequency the sensitivity adds ``G 2 w_e w_s T2^2 / (1 + (w_s T2)^2)`` (the
    steady-state gain; ``w_e`` stator, ``w_s`` slip frequency): larger than ``G`` at speed and
    load, zero at no load, negative in regeneration.
    """
    G = psi * psi / L2
    return kappa / G, bandwidth_rad_s * (1.0 + kappa) / G


def afo_regeneration_gain(
    R1: float, sigma_L1: float, M: float, L2: float, g1: float = 0.0, rho: float = 0.9
):
    """Flux-equation gain ``g2 = -rho (R1 + sigma L1 g1) L2/M`` (ohm) of the AFO.

    With ``rho = 1`` it cancels the slip term of the steady-state speed sensitivity
    (:func:`afo_dc_sensitivity`), so that the adaptation keeps its sign in regeneration; but
    the flux equation then integrates the voltage model with no damping at zero stator
    frequency (an undamped error mode). ``rho < 1`` keeps a damping ``~ (1 - rho)`` and shrinks
    the unstable regenerating band of the plain observer, ``|w_e| < |w_s| R1 / (sigma L1/T2 +
    k^2 R2)``, to ``|w_e| < (1 - rho) |w_s| (R1 + sigma L1 g1) / (sigma L1/T2 + k^2 R2 + rho
    (R1 + sigma L1 g1))`` (0.3 rad/s instead of 3.0 at rated slip for Table IV, rho = 0.9).
    """
    return -rho * (R1 + sigma_L1 * g1) * L2 / M


def default_afo_gains(
    psi: float,
    R1: float,
    R2: float,
    sigma_L1: float,
    M: float,
    L2: float,
    g1: float,
    bandwidth_rad_s: float,
    R1_rate_rad_s: float,
    R2_rate_rad_s: float,
    injection: float = 0.0,
    injection_rad_s: float = 0.0,
):
    """AFO adaptation gains ``Kp, Ki, k_R1, k_R2``.

    At high frequency a speed error ``dw = w_r - w_r_hat`` drives the current error as
    ``sigma L1 p e = -j k psi dw - (R_sigma + sigma L1 g1) e``, so ``eps = Im(conj(e) lam_hat)
    = (k psi^2/sigma L1) dw / (s + c1)``, ``c1 = R_sigma/sigma L1 + g1``. The PI ``Kp + Ki/s``
    with ``Ki/Kp = c1`` cancels that pole and leaves ``Kp k psi^2/(sigma L1 s)``::

        Kp = a sigma L1 / (k psi^2),       Ki = Kp c1

    The same reasoning for the resistance laws gives rates ``a_R1``, ``a_R2``, with ``|i| =
    i_d = psi/M`` for R1 and, for R2, the mean square of the in-phase part of ``lam - M i``
    under a flux injection of relative amplitude ``A`` at ``w_inj`` (``lam - M i_d = -T2 p
    lam``): ``d2 = (A psi T2 w_inj)^2 / (2 (1 + (T2 w_inj)^2))`` (``psi^2`` without one)::

        k_R1 = a_R1 sigma L1 c1 / i_d^2,       k_R2 = a_R2 L2 sigma L1 c1 / (k d2)
    """
    k = M / L2
    R_sig = R1 + k * k * R2
    c1 = R_sig / sigma_L1 + g1
    Kp = bandwidth_rad_s * sigma_L1 / (k * psi * psi)
    i_d = psi / M
    k_R1 = R1_rate_rad_s * sigma_L1 * c1 / (i_d * i_d)
    T2 = L2 / R2
    x = T2 * injection_rad_s
    d2 = (injection * psi * x) ** 2 / (2.0 * (1.0 + x * x)) if injection > 0 else psi * psi
    k_R2 = R2_rate_rad_s * L2 * sigma_L1 * c1 / (k * d2)
    return Kp, Kp * c1, k_R1, k_R2


def afo_dc_sensitivity(R1, R2, sigma_L1, M, L2, w_e, w_s, g1=0.0, g2=0.0):
    """Steady-state ``d eps / d(w_r - w_r_hat)`` of the AFO divided by ``k psi^2`` (1/ohm).

    From the error equations in steady state at stator frequency ``w_e`` and slip ``w_s``::

        e = k w_e dw psi / D,
        D = (1/T2 + j w_s)(j w_e sigma L1 + R_sigma + sigma L1 g1) - (1/T2 - j w_r)(k^2 R2 - k g2)

    so ``eps = k psi^2 w_e Im(D) / |D|^2 dw``; the adaptation is stable in steady state where
    this is positive.
    """
    k = M / L2
    T2 = L2 / R2
    w_r = w_e - w_s
    R_sig = R1 + k * k * R2
    D = (1 / T2 + 1j * w_s) * (1j * w_e * sigma_L1 + R_sig + sigma_L1 * g1) - (
        1 / T2 - 1j * w_r
    ) * (k * k * R2 - k * g2)
    return w_e * D.imag / abs(D) ** 2


def afo_linearised(R1, R2, Ll1, Ll2, M, psi, w_e, w_s, g1, g2, Kp, Ki):
    """State matrix (5 x 5, real) of the AFO's error dynamics with its speed adaptation.

    Linearised about a steady state (rotor flux ``psi`` on the d axis of the frame turning at
    ``w_e``, true speed ``w_r = w_e - w_s`` constant, exact parameters), in that frame, states
    ``(Re e_i, Im e_i, Re e_lam, Im e_lam, z)`` with ``e = x - x_hat`` and ``z = \\int eps``::

        p e_i   = -(j w_e + R_sigma/sigma L1 + g1) e_i + (k/sigma L1)(1/T2 - j w_r) e_lam
                  - j (k/sigma L1) psi dw
        p e_lam = (M/T2 - g2) e_i - (1/T2 + j w_s) e_lam + j psi dw
        dw      = -(Kp eps + Ki z),      eps = -psi Im(e_i),      p z = eps

    The estimator is locally stable where every eigenvalue has a negative real part.
    """
    L1, L2 = Ll1 + M, Ll2 + M
    sL1 = L1 - M * M / L2
    k = M / L2
    T2 = L2 / R2
    w_r = w_e - w_s
    R_sig = R1 + k * k * R2
    a11 = -(1j * w_e + R_sig / sL1 + g1)
    a12 = (k / sL1) * (1 / T2 - 1j * w_r)
    a21 = M / T2 - g2
    a22 = -(1 / T2 + 1j * w_s)
    b1 = -1j * (k / sL1) * psi  # coefficient of dw in p e_i
    b2 = 1j * psi
    A = np.zeros((5, 5))

    def cplx(row, col, c):  # complex coefficient c times the complex state at col
        A[row, col] += c.real
        A[row, col + 1] += -c.imag
        A[row + 1, col] += c.imag
        A[row + 1, col + 1] += c.real

    cplx(0, 0, complex(a11))
    cplx(0, 2, complex(a12))
    cplx(2, 0, complex(a21))
    cplx(2, 2, complex(a22))
    # dw = -(Kp eps + Ki z), eps = -psi Im(e_i): dw = Kp psi e_iq - Ki z
    dw_row = np.zeros(5)
    dw_row[1] = Kp * psi
    dw_row[4] = -Ki
    for r, b in ((0, b1), (2, b2)):
        A[r] += b.real * dw_row
        A[r + 1] += b.imag * dw_row
    A[4, 1] = -psi
    return A


def default_ekf_noise(Ts, sigma_L1, psi, R2, voltage_V, flux_Wb_s, accel_rad_s2, R2_ohm_s, i_A):
    """EKF noise ``(q[6], r, p0[6])`` per period.

    Each process noise is the change one period of the named uncertainty makes, held over the
    period: current ``(sigma_v Ts / sigma L1)^2`` (a voltage error sigma_v), flux
    ``(sigma_lam' Ts)^2``, speed ``(a Ts)^2`` (an acceleration a, electrical), R2
    ``(r' Ts)^2`` (a drift rate r'); measurement ``r = sigma_i^2``. Initial covariance:
    currents ``r``, fluxes ``(0.2 psi)^2``, speed ``(20 rad/s)^2``, R2 ``(0.3 R2)^2``.
    """
    qi = (voltage_V * Ts / sigma_L1) ** 2
    ql = (flux_Wb_s * Ts) ** 2
    q = np.array([qi, qi, ql, ql, (accel_rad_s2 * Ts) ** 2, (R2_ohm_s * Ts) ** 2])
    r = i_A * i_A
    p0 = np.array([r, r, (0.2 * psi) ** 2, (0.2 * psi) ** 2, 400.0, (0.3 * R2) ** 2])
    return q, r, p0
