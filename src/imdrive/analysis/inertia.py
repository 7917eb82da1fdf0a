"""The rotor inertia a motor of a given size has, for a nameplate that does not give one.

A rotor's inertia grows with its volume times its radius squared, ``J ~ rho D^4 L``, and the
rotor volume with the rated torque (the output equation, Esson's rule: ``T = 2 sigma_tan V_r``
with a tangential stress ``sigma_tan`` that changes slowly with size; Pyrhonen, Jokinen,
Hrabovcova, *Design of Rotating Electrical Machines*, Wiley, 2008, ch. 6). The rated torque
``T_n = P / w_m`` therefore carries both the power and the pole number, and the default is a
power law in it::

    J = k_J (T_n / 1 N m)^a_J,    T_n = P / w_m,    w_m = 2 pi n / 60

with :data:`INERTIA_COEFFICIENT_KGM2` ``k_J`` and :data:`INERTIA_EXPONENT` ``a_J``.

**The constants are imdrive's own fit, not a published correlation** (none with its numbers
was found to cite): a least-squares line in ``log J`` against ``log T_n`` through the 17 rows
of one manufacturer's catalogue (SOGA MT3 IE3, 0.75-22 kW, 2 and 4 poles). They are checked,
not refitted, on 110 other motors: Motive's Delphi catalogue (0.75-315 kW, 2-8 poles), one
Sgath and one WAT motor, and Krause et al.'s 500 and 2250 hp machines. The data, their sources
and the comparison are in ``imdrive/studies/data/catalogue_inertia.csv`` and
:mod:`imdrive.studies.inertia_catalogue` (the table of docs/nameplate.md). Above 22 kW, an
extrapolation of the fit, the law is within a factor of 1.5 of 39 of the 44 motors (30 kW -
1.68 MW) and of 2.1 of all; up to 22 kW it runs high on the other manufacturers' lighter
rotors (median 1.37 times, at most 2.7).

An inertia given on the plate that is more than :data:`INERTIA_WARN_FACTOR` times off this
size class is warned about (:func:`inertia_problem`), not refused: a plate's J may include a
coupling or a flywheel.
"""

from __future__ import annotations

import math

__all__ = [
    "INERTIA_COEFFICIENT_KGM2",
    "INERTIA_EXPONENT",
    "INERTIA_WARN_FACTOR",
    "inertia_constant_s",
    "inertia_problem",
    "rotor_inertia_kgm2",
]

#: ``k_J`` of ``J = k_J (T_n / 1 N m)^a_J``, kg m^2 (imdrive's fit, module docstring).
INERTIA_COEFFICIENT_KGM2 = 1.96e-4

#: ``a_J`` of ``J = k_J (T_n / 1 N m)^a_J``, dimensionless (imdrive's fit; a rotor of fixed
#: shape and tangential stress would give 5/3).
INERTIA_EXPONENT = 1.426

#: A given J more than this factor above or below :func:`rotor_inertia_kgm2` is warned about
#: (the catalogue motors of the fit are within a factor of 1.7 of it).
INERTIA_WARN_FACTOR = 4.0


def rotor_inertia_kgm2(power_W: float, speed_rpm: float) -> float:
    """The rotor inertia of a motor of this size: ``J = k_J (T_n / 1 N m)^a_J``.

    Parameters
    ----------
    power_W : float
        Rated shaft power ``P``, W.
    speed_rpm : float
        Rated speed ``n``, rpm.

    Returns
    -------
    float
        ``J``, kg m^2, with ``T_n = P / (2 pi n / 60)`` in N m and the constants
        :data:`INERTIA_COEFFICIENT_KGM2`, :data:`INERTIA_EXPONENT` (imdrive's fit to catalogue
        data from 0.75 to 22 kW; above, an extrapolation checked on catalogue motors to 1.68 MW).
    """
    torque_Nm = power_W / (speed_rpm * math.pi / 30.0)
    return INERTIA_COEFFICIENT_KGM2 * torque_Nm**INERTIA_EXPONENT


def inertia_constant_s(J_kgm2: float, power_W: float, speed_rpm: float) -> float:
    """The inertia constant ``H = J w_m^2 / (2 P)``: the stored energy at rated speed over
    the rated power.

    Parameters
    ----------
    J_kgm2 : float
        Inertia, kg m^2.
    power_W, speed_rpm : float
        Rated power (W) and speed (rpm); ``w_m = 2 pi n / 60``.

    Returns
    -------
    float
        ``H``, s.
    """
    w_m = speed_rpm * math.pi / 30.0
    return J_kgm2 * w_m**2 / (2.0 * power_W)


def inertia_problem(J_kgm2: float, power_W: float, speed_rpm: float) -> str | None:
    """What is suspicious about a given rotor inertia, or None.

    Parameters
    ----------
    J_kgm2 : float
        The inertia given, kg m^2.
    power_W, speed_rpm : float
        Rated power (W) and speed (rpm).

    Returns
    -------
    str or None
        One line when ``J`` is more than :data:`INERTIA_WARN_FACTOR` times above or below
        :func:`rotor_inertia_kgm2`, naming both and the inertia constant; else None.
    """
    size = rotor_inertia_kgm2(power_W, speed_rpm)
    ratio = J_kgm2 / size
    if 1.0 / INERTIA_WARN_FACTOR <= ratio <= INERTIA_WARN_FACTOR:
        return None
    H = inertia_constant_s(J_kgm2, power_W, speed_rpm)
    return (
        f"{J_kgm2:.4g} kg m^2 (H = {H:.3g} s) is {ratio:.3g} times the {size:.3g} kg m^2 of a "
        f"rotor of this size (outside 1/{INERTIA_WARN_FACTOR:g}-{INERTIA_WARN_FACTOR:g} times): "
        "check the unit (kg m^2, not kg cm^2 or lb ft^2) and whether a load is included"
    )
