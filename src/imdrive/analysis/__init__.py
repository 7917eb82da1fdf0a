"""Steady-state analysis: equivalent circuit, breakdown torque, field-oriented operating point.

Pure numpy/scipy (no numba). SI units throughout; rpm only where a name says so.

Conventions
-----------
The package uses the amplitude-invariant Clarke transform (see :mod:`imdrive`): the magnitude of a
space vector equals the PEAK value of the balanced phase quantity. All phasors here are therefore
**peak-value phasors**, and a steady-state space vector in the synchronous frame *is* the phasor.
Power and torque carry the factor 3/2::

    P = 1.5 Re(V I*),   T_e = 1.5 n_p Im(psi_s* i_s) = 1.5 n_p (M/L2) Im(psi_r* i_s)

With rms phasors (V_rms = V_peak/sqrt 2) the same quantities read ``P = 3 Re(V_rms I_rms*)``, the
textbook per-phase form; ``1.5 |I|^2 = 3 |I_rms|^2``.

Steady state of the machine model
---------------------------------
In the frame rotating at the supply (electrical) frequency ``w_e`` all quantities are constant and
the model of :mod:`imdrive.machine` becomes, with the slip frequency ``w_sl = w_e - w_r = s w_e``::

    V1 = R1 I1 + j w_e psi_s,       psi_s = L1 I1 + M I2
    0  = R2 I2 + j w_sl psi_r,      psi_r = M I1 + L2 I2

Dividing the rotor equation by ``s`` gives the T-equivalent circuit: stator branch
``R1 + j w_e Ll1``, magnetising branch ``j w_e M``, rotor branch ``R2/s + j w_e Ll2``. Here ``I2``
is the rotor current with the sign of the machine model (``psi_r = M I1 + L2 I2``, so
``I2 = -I2'`` of the textbook circuit where ``I2'`` flows out of the magnetising node) and the
magnetising current is ``Im = I1 + I2``.

Sensorless detuning law (Schauder's MRAS speed feedback with a wrong R2_hat)
--------------------------------------------------------------------------
Let ``k = R2_hat / R2`` (``T2 = L2/R2``, ``T2_hat = L2/R2_hat``, so ``T2/T2_hat = k``). In steady
state the stator current is a constant ``I`` in the synchronous frame. The reference (voltage)
model returns the true rotor flux; the true rotor equation gives::

    psi_r     = M I / (1 + j (w_e - w_r)     T2)
    psi_r_hat = M I / (1 + j (w_e - w_r_hat) T2_hat)      (adjustable model, eq. (2))

The adaptation ``w_r_hat = K1 e + K2 int e``, ``e = Im(psi_r_hat* psi_r)``, is at rest only when
``e = 0``: the two vectors are parallel. Both have the form ``M I / (1 + j x)``, whose angle
``arg I - atan x`` is injective in ``x`` and whose magnitude depends on the same ``x``, so ``e = 0``
forces ``(w_e - w_r_hat) T2_hat = (w_e - w_r) T2``, i.e. ``psi_r_hat = psi_r`` exactly (the
steady-state flux error, including its d component ``e_d0``, vanishes), and::

    w_e - w_r_hat = k (w_e - w_r)                         (estimated slip = k * true slip)

Indirect FOC fed by the estimate imposes ``w_e = w_r_hat + w_sl*`` with
``w_sl* = (R2_hat/L2) iq*/id*``. Hence ``k (w_e - w_r) = w_sl*`` and the true slip is::

    w_sl = w_e - w_r = w_sl*/k = (R2/L2) iq*/id*

which is exactly the correctly tuned slip for the imposed currents: ``psi_r = M I/(1 + j iq/id)
= M id`` is real, the orientation is correct and ``T_e = 1.5 n_p (M/L2) psi_r iq`` is the intended
torque. The speed loop drives ``w_r_hat`` to the reference ``w_ref``, so::

    w_r = w_e - w_sl = w_ref + w_sl* - w_sl = w_ref + w_sl (k - 1)
    w_m - w_m_ref = (w_sl / n_p) (R2_hat/R2 - 1)

The actual speed exceeds the reference by ``(k - 1)`` times the true mechanical slip: above it for a
motoring load and ``R2_hat > R2``. No linearisation is involved; the law only assumes the
voltage model is exact (R1, sigma L1 correct) and the speed loop has integral action.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from imdrive.config.machine import MachineParams
from imdrive.errors import ConfigError

__all__ = [
    "SteadyState",
    "FOCOperatingPoint",
    "equivalent_circuit",
    "breakdown",
    "breakdown_thevenin",
    "foc_operating_point",
    "detuning_speed_error_rpm",
    "plot_speed_error_vs_R2",
]

_RPM_PER_RAD_S = 30.0 / math.pi  # rpm per (mechanical) rad/s


def _scalar_or_array(x):
    """0-d arrays become Python scalars (float or complex); others stay arrays."""
    x = np.asarray(x)
    return x[()] if x.ndim == 0 else x


# ------------------------------------------------------------------------------------------
# equivalent circuit


@dataclass(frozen=True)
class SteadyState:
    """Sinusoidal steady state of the T-equivalent circuit (peak-value phasors, per phase).

    Every field is a scalar or a numpy array broadcast from the inputs of
    :func:`equivalent_circuit`. Phasors are referred to the stator voltage (``V1`` real).

    Attributes
    ----------
    slip : float or ndarray
        Slip ``s = (w_e - w_r) / w_e``, dimensionless.
    f_Hz, w_e : float or ndarray
        Supply frequency, Hz, and electrical angular frequency ``2 pi f``, rad/s.
    w_m, speed_rpm : float or ndarray
        Mechanical speed ``(1 - s) w_e / n_p``, rad/s and rpm.
    V1 : float or ndarray
        Stator phase-voltage phasor, peak, V: ``sqrt(2/3) V_ll_rms``.
    I1, I2, Im : complex or ndarray
        Stator, rotor (machine-model sign) and magnetising ``I1 + I2`` current phasors, peak, A.
    I1_peak_A, I1_rms_A, I2_peak_A, I2_rms_A, Im_peak_A : float or ndarray
        Their magnitudes, A (rms = peak / sqrt 2).
    psi_s_Wb, psi_r_Wb : float or ndarray
        Stator and rotor flux-linkage magnitudes ``|L1 I1 + M I2|``, ``|M I1 + L2 I2|``, Wb.
    P_in_W : float or ndarray
        Electrical input power ``1.5 Re(V1 I1*)``, W.
    P_cu1_W, P_cu2_W : float or ndarray
        Stator and rotor copper losses ``1.5 R |I|^2``, W.
    P_airgap_W : float or ndarray
        Air-gap power ``1.5 |I2|^2 R2 / s = T_e w_e / n_p``, W.
    P_mech_W : float or ndarray
        Internal mechanical power ``T_e w_m = (1 - s) P_airgap``, W (friction not subtracted).
    torque_Nm : float or ndarray
        Electromagnetic torque, N m.
    power_factor : float or ndarray
        ``cos(arg V1 - arg I1) = P_in / (1.5 |V1| |I1|)``.
    """

    slip: np.ndarray
    f_Hz: np.ndarray
    w_e: np.ndarray
    w_m: np.ndarray
    speed_rpm: np.ndarray
    V1: np.ndarray
    I1: np.ndarray
    I2: np.ndarray
    Im: np.ndarray
    I1_peak_A: np.ndarray
    I1_rms_A: np.ndarray
    I2_peak_A: np.ndarray
    I2_rms_A: np.ndarray
    Im_peak_A: np.ndarray
    psi_s_Wb: np.ndarray
    psi_r_Wb: np.ndarray
    P_in_W: np.ndarray
    P_cu1_W: np.ndarray
    P_cu2_W: np.ndarray
    P_airgap_W: np.ndarray
    P_mech_W: np.ndarray
    torque_Nm: np.ndarray
    power_factor: np.ndarray


def equivalent_circuit(machine: MachineParams, V_ll_rms, f_Hz, slip) -> SteadyState:
    """Solve the exact T-equivalent circuit for given supply and slip.

    Parameters
    ----------
    machine : MachineParams
    V_ll_rms : float or array_like
        Line-to-line rms supply voltage, V (>= 0).
    f_Hz : float or array_like
        Supply frequency, Hz (> 0).
    slip : float or array_like
        Slip ``s = (w_e - w_r)/w_e``; any real value (``s = 0`` synchronous, ``s = 1`` standstill,
        ``s < 0`` generating). The three inputs broadcast against each other.

    Returns
    -------
    SteadyState

    Notes
    -----
    With reactances ``X_l1 = w_e Ll1``, ``X_l2 = w_e Ll2``, ``X_M = w_e M``, ``X_L1 = w_e L1``,
    ``X_L2 = w_e L2`` and the peak phase voltage ``V1 = sqrt(2/3) V_ll_rms``, the rotor equation
    ``0 = R2 I2 + j s w_e (M I1 + L2 I2)`` gives, without dividing by ``s``::

        I2 = -j s X_M I1 / (R2 + j s X_L2)
        Z  = R1 + j X_L1 + s X_M^2 / (R2 + j s X_L2)
           = R1 + j X_l1 + (j X_M || (R2/s + j X_l2))            (for s != 0)
        I1 = V1 / Z

    The torque follows from the air-gap power ``P_ag = 1.5 |I2|^2 R2 / s`` and
    ``T_e = P_ag n_p / w_e``::

        T_e = 1.5 n_p |I2|^2 R2 / (s w_e) = 1.5 n_p s X_M^2 R2 |I1|^2 / (w_e |R2 + j s X_L2|^2)

    which equals the textbook ``3 n_p |I2_rms|^2 R2 / (s w_e)`` because ``|I2|^2 = 2 |I2_rms|^2``.
    The second form is finite at ``s = 0`` (torque 0, ``I1 = V1/(R1 + j X_L1)``).
    """
    V_ll = np.asarray(V_ll_rms, dtype=float)
    f = np.asarray(f_Hz, dtype=float)
    s = np.asarray(slip, dtype=float)
    if np.any(f <= 0) or not np.all(np.isfinite(f)):
        raise ConfigError("f_Hz", "must be finite and > 0")
    if np.any(V_ll < 0) or not np.all(np.isfinite(V_ll)):
        raise ConfigError("V_ll_rms", "must be finite and >= 0")
    if not np.all(np.isfinite(s)):
        raise ConfigError("slip", "must be finite")
    V_ll, f, s = np.broadcast_arrays(V_ll, f, s)

    n_p = machine.pole_pairs
    R1, R2 = machine.R1_ohm, machine.R2_ohm
    w_e = 2.0 * np.pi * f
    X_M = w_e * machine.M_H
    X_L1 = w_e * machine.L1_H
    X_L2 = w_e * machine.L2_H
    V1 = np.sqrt(2.0 / 3.0) * V_ll + 0j

    rotor_den = R2 + 1j * s * X_L2  # never zero: R2 > 0
    Z = R1 + 1j * X_L1 + s * X_M**2 / rotor_den
    I1 = V1 / Z
    I2 = -1j * s * X_M * I1 / rotor_den
    Im = I1 + I2
    psi_s = machine.L1_H * I1 + machine.M_H * I2
    psi_r = machine.M_H * I1 + machine.L2_H * I2

    I1_abs2 = np.abs(I1) ** 2
    torque = 1.5 * n_p * s * X_M**2 * R2 * I1_abs2 / (w_e * np.abs(rotor_den) ** 2)
    P_in = 1.5 * np.real(V1 * np.conj(I1))
    P_cu1 = 1.5 * R1 * I1_abs2
    P_cu2 = 1.5 * R2 * np.abs(I2) ** 2
    P_ag = torque * w_e / n_p
    w_m = (1.0 - s) * w_e / n_p
    S_abs = 1.5 * np.abs(V1) * np.sqrt(I1_abs2)
    with np.errstate(invalid="ignore", divide="ignore"):
        pf = np.where(S_abs > 0, P_in / np.where(S_abs > 0, S_abs, 1.0), np.nan)

    r = _scalar_or_array
    return SteadyState(
        slip=r(s),
        f_Hz=r(f),
        w_e=r(w_e),
        w_m=r(w_m),
        speed_rpm=r(w_m * _RPM_PER_RAD_S),
        V1=r(V1.real),
        I1=r(I1),
        I2=r(I2),
        Im=r(Im),
        I1_peak_A=r(np.abs(I1)),
        I1_rms_A=r(np.abs(I1) / np.sqrt(2.0)),
        I2_peak_A=r(np.abs(I2)),
        I2_rms_A=r(np.abs(I2) / np.sqrt(2.0)),
        Im_peak_A=r(np.abs(Im)),
        psi_s_Wb=r(np.abs(psi_s)),
        psi_r_Wb=r(np.abs(psi_r)),
        P_in_W=r(P_in),
        P_cu1_W=r(P_cu1),
        P_cu2_W=r(P_cu2),
        P_airgap_W=r(P_ag),
        P_mech_W=r(torque * w_m),
        torque_Nm=r(torque),
        power_factor=r(pf),
    )


# ------------------------------------------------------------------------------------------
# breakdown (pull-out) torque


def _check_supply(V_ll_rms, f_Hz) -> tuple[float, float]:
    V = float(V_ll_rms)
    f = float(f_Hz)
    if not (math.isfinite(V) and V > 0):
        raise ConfigError("V_ll_rms", "must be finite and > 0")
    if not (math.isfinite(f) and f > 0):
        raise ConfigError("f_Hz", "must be finite and > 0")
    return V, f


def breakdown(machine: MachineParams, V_ll_rms: float, f_Hz: float) -> tuple[float, float]:
    """Breakdown (maximum motoring) torque and its slip, found numerically on the exact circuit.

    Parameters
    ----------
    machine : MachineParams
    V_ll_rms : float
        Line-to-line rms voltage, V.
    f_Hz : float
        Supply frequency, Hz.

    Returns
    -------
    slip_bd : float
        Slip at which ``T_e(s)`` of :func:`equivalent_circuit` is maximal (``s > 0``).
    torque_bd : float
        The maximal torque, N m.

    Notes
    -----
    ``T_e(s)`` is evaluated on a logarithmic grid ``1e-6 <= s <= 1e3`` to bracket the maximum; the
    root of ``dT_e/ds`` (central difference, relative step 1e-5, truncation error ~1e-10) is then
    found by Brent's method with ``xtol = 1e-14``. The result agrees with the closed form of
    :func:`breakdown_thevenin` to ~1e-9 relative in slip and ~1e-14 in torque.
    """
    V, f = _check_supply(V_ll_rms, f_Hz)

    def torque(s):
        return equivalent_circuit(machine, V, f, s).torque_Nm

    grid = np.logspace(-6.0, 3.0, 901)
    T = torque(grid)
    i = int(np.argmax(T))
    if i == 0 or i == grid.size - 1:  # pragma: no cover - impossible for a T-circuit
        raise RuntimeError("breakdown slip outside 1e-6 .. 1e3")

    def dT_ds(s):
        h = 1e-5 * s
        return (torque(s + h) - torque(s - h)) / (2.0 * h)

    s_bd = brentq(dT_ds, grid[i - 1], grid[i + 1], xtol=1e-14, rtol=4 * np.finfo(float).eps)
    return float(s_bd), float(torque(s_bd))


def breakdown_thevenin(machine: MachineParams, V_ll_rms: float, f_Hz: float) -> tuple[float, float]:
    """Closed-form breakdown slip and torque via the Thevenin equivalent of the stator side.

    Parameters
    ----------
    machine : MachineParams
    V_ll_rms : float
        Line-to-line rms voltage, V.
    f_Hz : float
        Supply frequency, Hz.

    Returns
    -------
    slip_bd : float
    torque_bd : float
        N m.

    Notes
    -----
    Seen from the rotor branch, the source ``V1`` (peak) behind ``R1 + j X_l1`` and the shunt
    ``j X_M`` is exactly (no approximation) a Thevenin source::

        V_th = V1 j X_M / (R1 + j (X_l1 + X_M))
        Z_th = R_th + j X_th = j X_M (R1 + j X_l1) / (R1 + j (X_l1 + X_M))

    so ``|I2| = |V_th| / |Z_th + R2/s + j X_l2|`` and, with ``x = R2/s``::

        T_e = 1.5 n_p |V_th|^2 x / (w_e ((R_th + x)^2 + (X_th + X_l2)^2))

    ``dT_e/dx = 0`` gives ``x = sqrt(R_th^2 + (X_th + X_l2)^2)``, hence::

        s_bd = R2 / sqrt(R_th^2 + (X_th + X_l2)^2)
        T_bd = 1.5 n_p |V_th|^2 / (2 w_e (R_th + sqrt(R_th^2 + (X_th + X_l2)^2)))

    (with rms ``V_th`` the leading factor would be 3 instead of 1.5).
    """
    V, f = _check_supply(V_ll_rms, f_Hz)
    w_e = 2.0 * math.pi * f
    X_l1 = w_e * machine.Ll1_H
    X_l2 = w_e * machine.Ll2_H
    X_M = w_e * machine.M_H
    V1 = math.sqrt(2.0 / 3.0) * V
    den = machine.R1_ohm + 1j * (X_l1 + X_M)
    V_th = V1 * 1j * X_M / den
    Z_th = 1j * X_M * (machine.R1_ohm + 1j * X_l1) / den
    root = math.hypot(Z_th.real, Z_th.imag + X_l2)
    s_bd = machine.R2_ohm / root
    T_bd = 1.5 * machine.pole_pairs * abs(V_th) ** 2 / (2.0 * w_e * (Z_th.real + root))
    return s_bd, T_bd


# ------------------------------------------------------------------------------------------
# field-oriented steady state


@dataclass(frozen=True)
class FOCOperatingPoint:
    """Steady state of an indirect-FOC drive with imposed currents and a rotor-resistance estimate.

    Attributes
    ----------
    speed_ref_rpm : float
        Speed reference of the speed loop, mechanical rpm.
    speed_rpm, w_m : float
        Actual mechanical speed, rpm and rad/s.
    speed_est_rpm : float
        Speed the speed controller sees (MRAS estimate, or the measurement), rpm.
    speed_error_rpm : float
        ``speed_rpm - speed_ref_rpm``.
    id_A, iq_A : float
        Imposed stator-current components in the controller's synchronous frame, peak, A.
    is_peak_A : float
        ``sqrt(id^2 + iq^2)``, A.
    w_sl : float
        True slip frequency ``w_e - w_r``, electrical rad/s.
    w_sl_cmd : float
        Slip frequency commanded by the controller, ``(R2_hat/L2) iq/id``, electrical rad/s.
    w_e, f_Hz : float
        Synchronous (stator) frequency, electrical rad/s and Hz.
    slip : float
        ``w_sl / w_e`` (nan when ``w_e = 0``).
    slip_mech_rpm : float
        True slip in mechanical rpm, ``w_sl / n_p * 30/pi``.
    psi_r_Wb : float
        True rotor-flux magnitude, Wb.
    flux_ref_Wb : float
        Commanded rotor flux ``M id``, Wb.
    orientation_error_rad : float
        Angle of the true rotor flux in the controller's frame (0: correct orientation), rad.
    torque_Nm : float
        Electromagnetic torque, N m (equals ``load_Nm + B w_m``).
    V_s_peak_V, V_ll_rms_V : float
        Stator-voltage magnitude (peak phase) and the equivalent line-to-line rms value, V.
    R2_ratio : float
        ``R2_hat / R2``.
    sensorless : bool
    """

    speed_ref_rpm: float
    speed_rpm: float
    w_m: float
    speed_est_rpm: float
    speed_error_rpm: float
    id_A: float
    iq_A: float
    is_peak_A: float
    w_sl: float
    w_sl_cmd: float
    w_e: float
    f_Hz: float
    slip: float
    slip_mech_rpm: float
    psi_r_Wb: float
    flux_ref_Wb: float
    orientation_error_rad: float
    torque_Nm: float
    V_s_peak_V: float
    V_ll_rms_V: float
    R2_ratio: float
    sensorless: bool


def _detuned_torque(machine: MachineParams, i_d: float, x, k: float):
    """Torque of the true machine with ``i_s = id (1 + j x)`` and true slip ``w_sl T2 = k x``.

    ``T_e = 1.5 n_p (M^2/L2) id^2 (1 + x^2) k x / (1 + k^2 x^2)`` (see foc_operating_point).
    """
    c = 1.5 * machine.pole_pairs * machine.M_H**2 / machine.L2_H * i_d**2
    return c * (1.0 + x * x) * k * x / (1.0 + (k * x) ** 2)


def _solve_detuned_x(machine: MachineParams, i_d: float, k: float, T_req: float) -> float:
    """Smallest ``|x| = |iq/id|`` on the rising branch where the detuned torque equals T_req."""
    if T_req == 0.0:
        return 0.0
    sign = 1.0 if T_req > 0 else -1.0
    target = abs(T_req)  # the torque is odd in x

    def g(x):
        return _detuned_torque(machine, i_d, x, k) - target

    hi = 1.0
    while g(hi) < 0.0:
        hi *= 2.0
        if hi > 1e12:  # pragma: no cover - torque grows without bound in x
            raise RuntimeError("no detuned operating point found")
    # for k >= 3 the torque is not monotone in x: take the first crossing, the one the speed loop
    # reaches when it raises iq from zero (for k < 3, dT/dx > 0 everywhere and it is unique)
    xs = np.linspace(0.0, hi, 4097)
    j = int(np.argmax(g(xs) >= 0.0))
    return sign * brentq(g, xs[j - 1], xs[j], xtol=1e-15, rtol=4 * np.finfo(float).eps)


def foc_operating_point(
    machine: MachineParams,
    speed_rpm: float,
    load_Nm: float,
    R2_ratio: float = 1.0,
    flux_ref_Wb: float | None = None,
    sensorless: bool = True,
) -> FOCOperatingPoint:
    """Steady state of an indirect field-oriented drive whose slip calculator uses ``R2_hat``.

    Parameters
    ----------
    machine : MachineParams
        The true machine. The controller knows every parameter exactly except
        ``R2_hat = R2_ratio * R2``.
    speed_rpm : float
        Speed reference, mechanical rpm. With integral action the speed loop brings its feedback
        (the MRAS estimate if ``sensorless``, else the measured speed) to this value.
    load_Nm : float
        Load torque, N m (positive opposes forward rotation). Viscous friction ``machine.B_Nms``
        is added: the machine delivers ``T_e = load_Nm + B w_m``.
    R2_ratio : float
        ``R2_hat / R2`` (> 0).
    flux_ref_Wb : float, optional
        Rotor-flux reference, Wb; the controller imposes ``id* = flux_ref / M``. Default
        ``machine.rated_flux_Wb``.
    sensorless : bool
        True: speed feedback from Schauder's MRAS (also using ``R2_hat``). False: measured speed.

    Returns
    -------
    FOCOperatingPoint

    Notes
    -----
    The controller imposes ``i_s = id + j iq`` in a frame rotating at ``w_e = w_fb + w_sl*``
    (``w_fb`` = electrical speed feedback), ``w_sl* = (R2_hat/L2) iq/id``. The true rotor equation
    in that frame, ``0 = R2 i_r + j w_sl psi_r`` with ``psi_r = M i_s + L2 i_r``, gives::

        psi_r = M i_s / (1 + j w_sl T2),       T2 = L2 / R2
        T_e   = 1.5 n_p (M/L2) Im(psi_r* i_s) = 1.5 n_p (M^2/L2) |i_s|^2 w_sl T2 / (1 + (w_sl T2)^2)

    and the stator voltage ``v = R1 i_s + j w_e psi_s``, ``psi_s = sigma L1 i_s + (M/L2) psi_r``.

    *Measured speed* (``sensorless=False``): ``w_fb = w_r``, so the true slip is ``w_sl*``. With
    ``x = iq/id`` and ``k = R2_ratio``, ``w_sl T2 = k x`` and::

        |psi_r| = M id sqrt((1 + x^2) / (1 + k^2 x^2)),
        T_e     = 1.5 n_p (M^2/L2) id^2 k x (1 + x^2) / (1 + k^2 x^2)

    The speed loop raises ``iq`` until ``T_e = load + B w_m`` (solved for ``x`` by Brent's method;
    ``dT_e/dx > 0`` for ``k < 3``). The speed is exact; for ``k > 1`` the commanded slip is too
    large and ``|psi_r| < M id`` at load (``k < 1``: flux above the reference).

    *MRAS speed* (``sensorless=True``): see the module docstring. The true slip is
    ``(R2/L2) iq/id``, the orientation is correct, ``psi_r = M id = flux_ref`` and::

        iq   = T_e L2 / (1.5 n_p M psi_r),   w_sl = (R2/L2) iq/id = R2 T_e / (1.5 n_p psi_r^2)
        w_m  = w_m_ref + (w_sl/n_p) (k - 1)

    With friction, ``T_e = load + B w_m`` is linear in ``T_e`` and is solved in closed form.
    """
    k = float(R2_ratio)
    if not (math.isfinite(k) and k > 0):
        raise ConfigError("R2_ratio", "must be finite and > 0")
    psi_ref = machine.rated_flux_Wb if flux_ref_Wb is None else float(flux_ref_Wb)
    if not (math.isfinite(psi_ref) and psi_ref > 0):
        raise ConfigError("flux_ref_Wb", "must be finite and > 0")
    n_p = machine.pole_pairs
    M, L2, R2 = machine.M_H, machine.L2_H, machine.R2_ohm
    T2 = L2 / R2
    B = machine.B_Nms
    w_m_ref = float(speed_rpm) / _RPM_PER_RAD_S
    load = float(load_Nm)
    i_d = psi_ref / M

    if sensorless:
        a = R2 / (1.5 * n_p**2 * psi_ref**2)  # w_m - w_m_ref = (k - 1) a T_e
        den = 1.0 - B * (k - 1.0) * a
        if den <= 0.0:
            raise ConfigError("R2_ratio", "no steady state: friction feedback through detuning")
        torque = (load + B * w_m_ref) / den
        i_q = torque * L2 / (1.5 * n_p * M * psi_ref)
        w_sl = (R2 / L2) * i_q / i_d
        w_m = w_m_ref + (k - 1.0) * w_sl / n_p
        w_m_est = w_m_ref
    else:
        w_m = w_m_ref
        w_m_est = w_m
        torque_req = load + B * w_m
        x = _solve_detuned_x(machine, i_d, k, torque_req)
        i_q = x * i_d
        w_sl = k * (R2 / L2) * i_q / i_d
        torque = float(_detuned_torque(machine, i_d, x, k))

    w_sl_cmd = k * (R2 / L2) * i_q / i_d
    w_e = n_p * w_m + w_sl
    i_s = complex(i_d, i_q)
    psi_r = M * i_s / complex(1.0, w_sl * T2)
    psi_s = machine.sigma * machine.L1_H * i_s + (M / L2) * psi_r
    v_s = machine.R1_ohm * i_s + 1j * w_e * psi_s
    V_peak = abs(v_s)
    return FOCOperatingPoint(
        speed_ref_rpm=float(speed_rpm),
        speed_rpm=w_m * _RPM_PER_RAD_S,
        w_m=w_m,
        speed_est_rpm=w_m_est * _RPM_PER_RAD_S,
        speed_error_rpm=(w_m - w_m_ref) * _RPM_PER_RAD_S,
        id_A=i_d,
        iq_A=i_q,
        is_peak_A=abs(i_s),
        w_sl=w_sl,
        w_sl_cmd=w_sl_cmd,
        w_e=w_e,
        f_Hz=w_e / (2.0 * math.pi),
        slip=w_sl / w_e if w_e != 0.0 else math.nan,
        slip_mech_rpm=w_sl / n_p * _RPM_PER_RAD_S,
        psi_r_Wb=abs(psi_r),
        flux_ref_Wb=psi_ref,
        orientation_error_rad=math.atan2(psi_r.imag, psi_r.real),
        torque_Nm=torque,
        V_s_peak_V=V_peak,
        V_ll_rms_V=V_peak * math.sqrt(1.5),
        R2_ratio=k,
        sensorless=bool(sensorless),
    )


def detuning_speed_error_rpm(
    machine: MachineParams,
    speed_rpm: float,
    load_Nm: float,
    R2_ratio,
    flux_ref_Wb: float | None = None,
):
    """Steady-state speed error of the MRAS-sensorless IFOC drive due to ``R2_hat != R2``, rpm.

    Parameters
    ----------
    machine : MachineParams
    speed_rpm : float
        Speed reference (= the MRAS estimate in steady state), mechanical rpm.
    load_Nm : float
        Load torque, N m (friction ``B w_m`` added).
    R2_ratio : float or array_like
        ``R2_hat / R2``.
    flux_ref_Wb : float, optional
        Rotor-flux reference, Wb (default ``machine.rated_flux_Wb``).

    Returns
    -------
    float or ndarray
        ``n_actual - n_ref = slip_mech_rpm (R2_ratio - 1)``, rpm, where
        ``slip_mech_rpm = (30/pi) R2 T_e / (1.5 n_p^2 psi_r^2)`` is the true mechanical slip.
    """
    ratios = np.asarray(R2_ratio, dtype=float)
    out = np.array(
        [
            foc_operating_point(machine, speed_rpm, load_Nm, r, flux_ref_Wb, True).speed_error_rpm
            for r in ratios.ravel()
        ]
    ).reshape(ratios.shape)
    return _scalar_or_array(out)


def plot_speed_error_vs_R2(machine: MachineParams, speed_rpm: float, loads_Nm, ratios, ax=None):
    """Plot the sensorless drive's steady-state speed error against ``R2_hat / R2``.

    Parameters
    ----------
    machine : MachineParams
    speed_rpm : float
        Speed reference, mechanical rpm.
    loads_Nm : iterable of float
        Load torques, N m; one curve each.
    ratios : array_like
        Values of ``R2_hat / R2`` on the horizontal axis.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; by default a new :class:`matplotlib.figure.Figure` is created (no pyplot
        global state, safe with the Agg backend).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    if ax is None:
        fig = Figure(figsize=(6.0, 4.0), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    r = np.asarray(ratios, dtype=float)
    for load in loads_Nm:
        err = detuning_speed_error_rpm(machine, speed_rpm, load, r)
        ax.plot(r, np.atleast_1d(err), marker=".", label=f"{load:g} N m")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.axvline(1.0, color="0.5", lw=0.8, ls=":")
    ax.set_xlabel(r"$\hat R_2 / R_2$")
    ax.set_ylabel("speed error $n - n^*$ (rpm)")
    ax.set_title(f"MRAS-sensorless IFOC, $n^*$ = {speed_rpm:g} rpm")
    ax.grid(True, alpha=0.3)
    ax.legend(title="load")
    return fig
