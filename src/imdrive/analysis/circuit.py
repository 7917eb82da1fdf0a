"""Sinusoidal steady state of the induction machine: T-equivalent circuit and breakdown torque.

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
the plant model of :mod:`imdrive.kernels.machine` becomes, with the slip frequency
``w_sl = w_e - w_r = s w_e``::

    V1 = R1 I1 + j w_e psi_s,       psi_s = L1 I1 + M I2
    0  = R2 I2 + j w_sl psi_r,      psi_r = M I1 + L2 I2

Dividing the rotor equation by ``s`` gives the T-equivalent circuit: stator branch
``R1 + j w_e Ll1``, magnetising branch ``j w_e M``, rotor branch ``R2/s + j w_e Ll2``. Here ``I2``
is the rotor current with the sign of the machine model (``psi_r = M I1 + L2 I2``, so
``I2 = -I2'`` of the textbook circuit where ``I2'`` flows out of the magnetising node) and the
magnetising current is ``Im = I1 + I2``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from imdrive.config.machine import MachineParams
from imdrive.errors import ConfigError

__all__ = ["SteadyState", "equivalent_circuit", "breakdown", "breakdown_thevenin"]

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
        ``cos(arg V1 - arg I1) = P_in / (1.5 |V1| |I1|)``, dimensionless.
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
        The machine's T-equivalent parameters.
    V_ll_rms : float or array_like
        Line-to-line rms supply voltage, V (>= 0).
    f_Hz : float or array_like
        Supply frequency, Hz (> 0).
    slip : float or array_like
        Slip ``s = (w_e - w_r)/w_e``, dimensionless; any real value (``s = 0`` synchronous,
        ``s = 1`` standstill, ``s < 0`` generating). The three inputs broadcast against each
        other.

    Returns
    -------
    SteadyState
        Currents, fluxes, powers and torque at every broadcast point.

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
    """Breakdown slip and (maximum motoring) torque, in that order, found numerically on the
    exact circuit.

    Parameters
    ----------
    machine : MachineParams
        The machine's T-equivalent parameters.
    V_ll_rms : float
        Line-to-line rms voltage, V.
    f_Hz : float
        Supply frequency, Hz.

    Returns
    -------
    slip_bd : float
        Slip at which ``T_e(s)`` of :func:`equivalent_circuit` is maximal (``s > 0``),
        dimensionless.
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
        The machine's T-equivalent parameters.
    V_ll_rms : float
        Line-to-line rms voltage, V.
    f_Hz : float
        Supply frequency, Hz.

    Returns
    -------
    slip_bd : float
        Breakdown slip (``s > 0``), dimensionless.
    torque_bd : float
        Breakdown (maximum motoring) torque, N m.

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
