"""Steady state of an indirect field-oriented drive whose R2 estimate is wrong.

Pure numpy/scipy (no numba). SI units throughout; rpm only where a name says so. Phasors are
peak-value phasors of the amplitude-invariant Clarke transform, as in
:mod:`imdrive.analysis.circuit`.

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

Relation to the paper's eq. (10)
--------------------------------
Eq. (10) is the MRAS error equation in the rotor-flux frame with the extra inputs an R2 error
adds, ``-(1/L2) lam_hat_0 (R2 - R2_hat) + (M/L2) i_0 (R2 - R2_hat)``; the paper concludes that
they keep ``e_d0`` from vanishing in steady state. Put the steady state above into it: with
``e_d0 = e_q0 = 0``, ``lam_hat_q0 = 0`` and ``lam_hat_d0 = M id``, the d row is ``0 = 0`` and
the q row reads ``0 = M id (w_r - w_r_hat) + (M/L2) iq (R2 - R2_hat)``, i.e.::

    w_r - w_r_hat = (R2_hat - R2) iq / (L2 id) = w_sl (k - 1)

which is the detuning law. The R2-error inputs of eq. (10) are balanced by the speed error,
not by a flux error: zero flux error is an equilibrium of eq. (10) itself.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from imdrive.analysis.circuit import _RPM_PER_RAD_S, _scalar_or_array
from imdrive.config.machine import MachineParams
from imdrive.errors import ConfigError, check_argument, check_number

__all__ = [
    "FOCOperatingPoint",
    "foc_operating_point",
    "detuning_speed_error_rpm",
    "field_weakened_flux_Wb",
]

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
        ``w_sl / w_e``, dimensionless (nan when ``w_e = 0``).
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
        ``R2_hat / R2``, dimensionless.
    sensorless : bool
        Speed feedback from the MRAS (True) or measured (False).
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


def _speed_loop_steady_state(machine, k, psi_ref, i_d, w_m_ref, load, sensorless):
    """Where the speed loop settles (see :func:`foc_operating_point`, Notes): mechanical speed
    and its feedback, rad/s; q current, A; true slip, rad/s; torque, N m."""
    n_p = machine.pole_pairs
    M, L2, R2 = machine.M_H, machine.L2_H, machine.R2_ohm
    B = machine.B_Nms
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
    return w_m, w_m_est, i_q, w_sl, torque


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
        ``R2_hat / R2``, dimensionless (> 0).
    flux_ref_Wb : float, optional
        Rotor-flux reference, Wb; the controller imposes ``id* = flux_ref / M``. Default
        ``machine.rated_flux_Wb``.
    sensorless : bool
        True: speed feedback from Schauder's MRAS (also using ``R2_hat``). False: measured speed.

    Returns
    -------
    FOCOperatingPoint
        Speeds, frequencies, fluxes, torque and voltage of the steady state.

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
    check_argument(machine, MachineParams, "machine", "a MachineParams (machine_preset(...))")
    speed_rpm = check_number(speed_rpm, "speed_rpm")  # a NaN gave a NaN operating point
    load_Nm = check_number(load_Nm, "load_Nm")
    k = check_number(R2_ratio, "R2_ratio")
    if not k > 0:
        raise ConfigError("R2_ratio", "must be finite and > 0")
    psi_ref = (
        machine.rated_flux_Wb if flux_ref_Wb is None else check_number(flux_ref_Wb, "flux_ref_Wb")
    )
    if not (math.isfinite(psi_ref) and psi_ref > 0):
        raise ConfigError("flux_ref_Wb", "must be finite and > 0")
    n_p = machine.pole_pairs
    M, L2, R2 = machine.M_H, machine.L2_H, machine.R2_ohm
    T2 = L2 / R2
    w_m_ref = float(speed_rpm) / _RPM_PER_RAD_S
    i_d = psi_ref / M
    w_m, w_m_est, i_q, w_sl, torque = _speed_loop_steady_state(
        machine, k, psi_ref, i_d, w_m_ref, float(load_Nm), sensorless
    )
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
    voltage_hold_V: float | None = None,
    flux_min_pu: float = 0.2,
):
    """Steady-state speed error of the MRAS-sensorless IFOC drive due to ``R2_hat != R2``, rpm.

    Parameters
    ----------
    machine : MachineParams
        The true machine (the controller knows all but R2).
    speed_rpm : float
        Speed reference (= the MRAS estimate in steady state), mechanical rpm.
    load_Nm : float
        Load torque, N m (friction ``B w_m`` added).
    R2_ratio : float or array_like
        ``R2_hat / R2``, dimensionless.
    flux_ref_Wb : float, optional
        Rotor-flux reference, Wb (default ``machine.rated_flux_Wb``).
    voltage_hold_V : float, optional
        A drive with voltage-feedback field weakening: the stator-voltage magnitude (peak
        phase) it holds, V (``control.field_weakening_voltage`` times ``Vdc/sqrt 3``). The
        flux is then :func:`field_weakened_flux_Wb`'s, not ``flux_ref_Wb``. Default: none.
    flux_min_pu : float
        The field weakening's lowest flux factor, dimensionless (``control.field_weakening_min``).

    Returns
    -------
    float or ndarray
        ``n_actual - n_ref = slip_mech_rpm (R2_ratio - 1)``, rpm, where
        ``slip_mech_rpm = (30/pi) R2 T_e / (1.5 n_p^2 psi_r^2)`` is the true mechanical slip
        (``psi_r`` the field-weakened flux when ``voltage_hold_V`` is given: the slip grows as
        ``1/psi_r^2``).
    """
    ratios = np.asarray(R2_ratio, dtype=float)
    out = []
    for r in ratios.ravel():
        psi = flux_ref_Wb
        if voltage_hold_V is not None:
            psi = field_weakened_flux_Wb(
                machine, speed_rpm, load_Nm, r, voltage_hold_V, flux_ref_Wb, flux_min_pu
            )
        out.append(foc_operating_point(machine, speed_rpm, load_Nm, r, psi, True).speed_error_rpm)
    return _scalar_or_array(np.array(out).reshape(ratios.shape))


#: step of the downward search for the field weakening's settling point, per-unit of the flux
_FW_SCAN_STEP = 0.005


def field_weakened_flux_Wb(
    machine: MachineParams,
    speed_rpm: float,
    load_Nm: float,
    R2_ratio: float = 1.0,
    voltage_hold_V: float = math.inf,
    flux_ref_Wb: float | None = None,
    flux_min_pu: float = 0.2,
    sensorless: bool = True,
    no_load_bound: bool = True,
) -> float:
    """The rotor flux a voltage-feedback field weakening settles at, Wb.

    The drive scales its flux reference by ``k``, ``dk/dt = rate (v_hold - |v_s|)``,
    ``flux_min_pu <= k <= 1`` (kernels/ifoc.py ``field_weakening``). In steady state either
    ``k = 1`` and ``|v_s| <= v_hold``, or ``|v_s(k psi_ref)| = v_hold``: coming down from 1 the
    integrator stops at the first (largest) such ``k``, or at the floor. ``|v_s|`` is the
    stator voltage of the steady state (:func:`foc_operating_point`: ``v_s = R1 i_s +
    j w_e psi_s`` with the speed loop's torque current at that flux, the MRAS detuning law's
    speed and slip when ``sensorless``).

    Parameters
    ----------
    machine : MachineParams
        The true machine.
    speed_rpm : float
        Speed reference, mechanical rpm.
    load_Nm : float
        Load torque, N m (friction added).
    R2_ratio : float
        ``R2_hat / R2``, dimensionless.
    voltage_hold_V : float
        Stator-voltage magnitude the field weakening holds (peak phase), V.
    flux_ref_Wb : float, optional
        Unweakened flux reference, Wb (default ``machine.rated_flux_Wb``).
    flux_min_pu : float
        Lowest flux factor, dimensionless (0, 1].
    sensorless : bool
        MRAS speed feedback (True) or measured speed.
    no_load_bound : bool
        The drive bounds ``k`` by the flux whose no-load voltage ``w_e (L1/M) k psi_ref`` is
        ``v_hold`` (``control.field_weakening_bound``, on by default): the steady state is
        then the largest ``k`` that meets both.

    Returns
    -------
    float
        ``k psi_ref``, Wb.
    """
    if not (voltage_hold_V > 0.0):
        raise ConfigError("voltage_hold_V", "must be > 0")
    if not (0.0 < flux_min_pu <= 1.0):
        raise ConfigError("flux_min_pu", "must be in (0, 1]")
    psi_ref = machine.rated_flux_Wb if flux_ref_Wb is None else float(flux_ref_Wb)

    L1_over_M = (machine.M_H + machine.Ll1_H) / machine.M_H

    def excess(k):
        # > 0 where k is beyond either bound, in units of v_hold
        op = foc_operating_point(machine, speed_rpm, load_Nm, R2_ratio, k * psi_ref, sensorless)
        out = op.V_s_peak_V / voltage_hold_V - 1.0
        if no_load_bound and op.w_e != 0.0:
            out = max(out, abs(op.w_e) * L1_over_M * k * psi_ref / voltage_hold_V - 1.0)
        return out

    if excess(1.0) <= 0.0:
        return psi_ref
    k_hi = 1.0
    while k_hi - _FW_SCAN_STEP >= flux_min_pu:
        k_lo = k_hi - _FW_SCAN_STEP
        if excess(k_lo) <= 0.0:
            return psi_ref * brentq(excess, k_lo, k_hi, xtol=1e-12)
        k_hi = k_lo
    return psi_ref * flux_min_pu
