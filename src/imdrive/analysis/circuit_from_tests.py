"""The T-circuit from test data: DC stator resistance, no-load test and locked-rotor test.

Where a motor has been tested, its circuit comes from measurements instead of a nameplate.
IEC 60034-28:2012 ("Rotating electrical machines - Part 28: Test methods for determining
quantities of equivalent circuit diagrams for three-phase low-voltage cage induction motors";
title, edition and scope checked against the standard's catalogue entry, which says its
formulae are for the star-equivalent circuit and that the 2012 edition admits a load-curve
test in place of the reverse-rotation and locked-rotor tests; its clauses and formulae were
not checked) defines tests of this kind. The reduction here takes a stator resistance, a
no-load test at rated voltage and frequency and a locked-rotor test (at reduced frequency if
wanted) through the classic no-load / locked-rotor equations of the textbooks and IEEE Std
112, made exact for the single-cage T-circuit instead of their usual approximations. It is not
a transcription of the standard's procedure.

Per phase, star equivalent, rms; ``V_ph = V / sqrt 3``; reactances at the no-load test's
frequency ``f``, scaled by ``f / f_k`` from the locked-rotor test's ``f_k``::

    no load (slip 0):   X1 + X_M = X_0 = Q_0 / (3 I_0^2),   Q_0 = sqrt((3 V_ph0 I_0)^2 - P_0^2)
                        P_Fe = P_0 - P_fw - 3 I_0^2 R1         iron loss (reported, not modelled)
    locked rotor (s=1): Z_k = V_phk / I_k (cos phi_k + j sin phi_k),
                        cos phi_k = P_k / (3 V_phk I_k)
                        Z_k = R1 + j a X1 + (j a X_M || (R2 + j a X2)),   a = f_k / f
    X1 = k (X1 + X2)                                             the leakage split (design letter)

The two real equations of the locked-rotor impedance give ``X1`` and ``R2`` (Newton from the
usual approximation ``R2 = (R_k - R1) ((X2 + X_M) / X_M)^2``, ``X1 + X2 = X_k``); ``X_M``
follows from ``X_0``. For data measured on a single-cage circuit the result is that circuit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import fsolve

from imdrive.errors import ConfigError, check_argument, check_number

__all__ = ["LockedRotorTest", "NoLoadTest", "TestCircuit", "circuit_from_tests"]


@dataclass(frozen=True)
class NoLoadTest:
    """A no-load test: the machine uncoupled, at (about) synchronous speed.

    Attributes
    ----------
    voltage_V, current_A : float
        Line voltage and current, rms, V and A.
    power_W : float
        Three-phase input power, W.
    frequency_Hz : float
        Supply frequency, Hz (the circuit's reactances are at this frequency).
    friction_windage_W : float
        Friction and windage loss, W (0: unknown, counted as iron loss).
    """

    voltage_V: float
    current_A: float
    power_W: float
    frequency_Hz: float
    friction_windage_W: float = 0.0


@dataclass(frozen=True)
class LockedRotorTest:
    """A locked-rotor test: the rotor held, at reduced voltage (and frequency, if wanted).

    Attributes
    ----------
    voltage_V, current_A : float
        Line voltage and current, rms, V and A.
    power_W : float
        Three-phase input power, W.
    frequency_Hz : float
        Supply frequency, Hz.
    """

    voltage_V: float
    current_A: float
    power_W: float
    frequency_Hz: float


@dataclass(frozen=True)
class TestCircuit:
    """The reduced circuit (ohm, reactances at the no-load test's frequency).

    Attributes
    ----------
    R1, R2, X1, X2, XM : float
        Stator and rotor resistance, stator and rotor leakage, magnetising reactance, ohm.
    iron_loss_W : float
        ``P_0 - P_fw - 3 I_0^2 R1``, W (the plant model has no iron-loss branch).
    residual : float
        Largest relative residual of the locked-rotor equations (0 when met).
    """

    __test__ = False  # not a pytest test class, whatever its name

    R1: float
    R2: float
    X1: float
    X2: float
    XM: float
    iron_loss_W: float
    residual: float


def _check(obj, names):
    for name in names:
        v = getattr(obj, name)
        if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
            raise ConfigError(name, f"must be a finite number > 0, got {v!r}")


def circuit_from_tests(
    R1_ohm: float, no_load: NoLoadTest, locked_rotor: LockedRotorTest, leakage_split: float = 0.5
) -> TestCircuit:
    """The T-circuit that reproduces a no-load and a locked-rotor test (module docstring).

    Parameters
    ----------
    R1_ohm : float
        Stator resistance per phase, star equivalent, ohm (DC measurement at the tests'
        temperature: half the line-to-line resistance of a star winding).
    no_load : NoLoadTest
        The no-load test.
    locked_rotor : LockedRotorTest
        The locked-rotor test.
    leakage_split : float
        ``X1 / (X1 + X2)`` (0.5 for NEMA designs A and D, 0.4 for B, 0.3 for C; IEEE Std 112).

    Returns
    -------
    TestCircuit
        The circuit, the iron loss it leaves out and the residual.

    Raises
    ------
    ConfigError
        A measurement out of range or tests no single-cage circuit meets, naming it.
    """
    check_argument(no_load, NoLoadTest, "no_load", "a NoLoadTest")
    check_argument(locked_rotor, LockedRotorTest, "locked_rotor", "a LockedRotorTest")
    R1_ohm = check_number(R1_ohm, "R1_ohm")
    leakage_split = check_number(leakage_split, "leakage_split")
    fields = ("voltage_V", "current_A", "power_W", "frequency_Hz")
    _check(no_load, fields)
    _check(locked_rotor, fields)
    if not (math.isfinite(R1_ohm) and R1_ohm > 0):
        raise ConfigError("R1_ohm", f"must be a finite number > 0, got {R1_ohm!r}")
    if not 0.05 <= leakage_split <= 0.95:
        raise ConfigError("leakage_split", "must be within 0.05-0.95")
    V0 = no_load.voltage_V / math.sqrt(3.0)
    S0 = 3.0 * V0 * no_load.current_A
    if not no_load.power_W < S0:
        raise ConfigError("no_load.power_W", f"must be below sqrt(3) V I = {S0:.5g} W")
    X0 = math.sqrt(S0**2 - no_load.power_W**2) / (3.0 * no_load.current_A**2)
    iron = no_load.power_W - no_load.friction_windage_W - 3.0 * no_load.current_A**2 * R1_ohm
    Vk = locked_rotor.voltage_V / math.sqrt(3.0)
    Sk = 3.0 * Vk * locked_rotor.current_A
    if not locked_rotor.power_W < Sk:
        raise ConfigError("locked_rotor.power_W", f"must be below sqrt(3) V I = {Sk:.5g} W")
    Rk = locked_rotor.power_W / (3.0 * locked_rotor.current_A**2)
    if not Rk > R1_ohm:
        raise ConfigError(
            "locked_rotor.power_W",
            f"P_k / (3 I_k^2) = {Rk:.4g} ohm is not above R1 = {R1_ohm:.4g} ohm",
        )
    a = locked_rotor.frequency_Hz / no_load.frequency_Hz
    Xk = math.sqrt((Sk / 3.0) ** 2 - (locked_rotor.power_W / 3.0) ** 2) / locked_rotor.current_A**2
    k = leakage_split

    def parts(x):
        Xl, R2 = np.exp(x)  # X1 + X2 at f, R2
        X1, X2 = k * Xl, (1.0 - k) * Xl
        XM = X0 - X1
        Z2 = R2 + 1j * a * X2
        Z = R1_ohm + 1j * a * X1 + 1j * a * XM * Z2 / (Z2 + 1j * a * XM)
        return X1, X2, XM, R2, Z

    def residuals(x):
        Z = parts(x)[4]
        return [(Z.real - Rk) / abs(complex(Rk, Xk)), (Z.imag - Xk) / abs(complex(Rk, Xk))]

    Xl0 = Xk / a
    if not k * Xl0 < X0:
        raise ConfigError(
            "locked_rotor.current_A",
            "the leakage reactance it implies exceeds the no-load reactance X1 + X_M",
        )
    XM0 = X0 - k * Xl0
    R20 = (Rk - R1_ohm) * (((1.0 - k) * Xl0 + XM0) / XM0) ** 2
    x, *_ = fsolve(residuals, [math.log(Xl0), math.log(R20)], xtol=1e-14, full_output=True)
    X1, X2, XM, R2, _ = parts(x)
    worst = float(np.max(np.abs(residuals(x))))
    if not XM > 0 or worst > 1e-6:
        raise ConfigError(
            "locked_rotor",
            f"no single-cage circuit meets the two tests (relative residual {worst:.2g})",
        )
    return TestCircuit(R1=R1_ohm, R2=R2, X1=X1, X2=X2, XM=XM, iron_loss_W=iron, residual=worst)
