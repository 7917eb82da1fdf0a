"""The scenario's speed reference and load as it states them, in rpm and N m, from either unit
of their pairs (``control.speed_ref_rpm`` / ``_pu``, ``load.torque_Nm`` / ``torque_pu``,
:data:`imdrive.config.pairs.PAIRS`): per-unit of the machine's rated speed and torque
(:func:`imdrive.config.rated.rated_point`). What the drive then follows (premagnetised,
ramps at the torque limit) is :func:`imdrive.config.sequence.sequence`.
"""

from __future__ import annotations

from imdrive.config.profiles import Profile
from imdrive.errors import ConfigError


def _rated(sc, key: str):
    from imdrive.config.rated import rated_point_or_none

    rp = rated_point_or_none(sc.machine)
    if rp is None:
        raise ConfigError(key, "needs the machine's rated point (a nameplate) to be per-unit")
    return rp


def stated_speed_ref_rpm(sc) -> Profile:
    """The speed reference as the scenario states it, rpm: ``control.speed_ref_pu`` times the
    rated speed when given, else ``control.speed_ref_rpm`` (not delayed, not limited)."""
    pu = sc.control.speed_ref_pu
    if pu is None:
        return sc.control.speed_ref_rpm
    return pu.scaled(_rated(sc, "control.speed_ref_pu").speed_rpm)


def stated_load_Nm(sc) -> Profile:
    """The load torque's profile as the scenario states it, N m: ``load.torque_pu`` times the
    rated torque when given, else ``load.torque_Nm`` (not delayed)."""
    pu = sc.load.torque_pu
    if pu is None:
        return sc.load.torque_Nm
    return pu.scaled(_rated(sc, "load.torque_pu").torque_Nm)
