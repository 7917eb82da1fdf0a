"""Settings of the simulated plant: windings' temperature, magnetic saturation, the
time-varying plant and the load torque (sections ``[plant]``, ``[plant.thermal]``,
``[plant.saturation]``, ``[load]``).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import model_validator

from imdrive.config.profiles import Profile
from imdrive.config.validation import Bool, Float, ProfileValues, setting, settings
from imdrive.errors import ConfigError

C = Profile.constant
PositiveProfile = Annotated[Profile, ProfileValues(gt=0.0)]


@settings("plant.thermal")
class ThermalSettings:
    """First-order thermal model of each winding (section ``[plant.thermal]``).

    ``tau dtheta/dt = Rth P_cu - (theta - theta_amb)`` and ``R = R_ref (1 + alpha (theta -
    theta_ref))``, one per winding (1: stator, 2: rotor). The thermal resistances default in
    per-unit of the machine's rated copper losses, the time constants are absolute
    (:func:`imdrive.config.scaled.plant_thermal_resistances`).
    """

    enabled: Annotated[
        Bool, setting("first-order thermal model of each winding; off: resistances stay put")
    ] = False
    alpha1_per_K: Annotated[
        Float, setting("temperature coefficient of the stator resistance (copper)", "1/K", ge=0.0)
    ] = 0.00393
    alpha2_per_K: Annotated[
        Float, setting("temperature coefficient of the rotor resistance (copper)", "1/K", ge=0.0)
    ] = 0.00393
    theta_ref_C: Annotated[
        Float,
        setting(
            "temperature at which R1_ohm and R2_ohm are given (above absolute zero, below "
            "copper's melting point)",
            "°C",
            gt=-273.15,
            le=1000.0,
        ),
    ] = 20.0
    theta_amb_C: Annotated[
        Float,
        setting(
            "ambient temperature (above absolute zero, below copper's melting point)",
            "°C",
            gt=-273.15,
            le=1000.0,
        ),
    ] = 20.0
    theta_init_C: Annotated[
        Float,
        setting(
            "winding temperature at t = 0 (above absolute zero, below copper's melting point)",
            "°C",
            gt=-273.15,
            le=1000.0,
        ),
    ] = 20.0
    Rth1_K_per_W: Annotated[
        Float | None,
        setting(
            "thermal resistance, stator winding to ambient; the absolute twin of Rth1_pu",
            "K/W",
            gt=0.0,
            derived=True,
        ),
    ] = None
    Rth1_pu: Annotated[
        Float | None,
        setting(
            "Rth1_K_per_W in per-unit of 80 K (the class B rise of IEC 60034-1) over the "
            "machine's rated stator copper losses 1.5 R1 I_peak²: the winding's rise at them "
            "over 80 K",
            gt=0.0,
            default_doc="unset: Rth1_K_per_W",
        ),
    ] = None
    tau1_s: Annotated[Float, setting("thermal time constant of the stator", "s", gt=0.0)] = 1200.0
    Rth2_K_per_W: Annotated[
        Float | None,
        setting(
            "thermal resistance, rotor winding to ambient; the absolute twin of Rth2_pu",
            "K/W",
            gt=0.0,
            derived=True,
        ),
    ] = None
    Rth2_pu: Annotated[
        Float | None,
        setting(
            "Rth2_K_per_W in per-unit of 80 K (the class B rise of IEC 60034-1) over the "
            "machine's rated rotor copper losses s T_rated w_sync: the winding's rise at them "
            "over 80 K",
            gt=0.0,
            default_doc="unset: Rth2_K_per_W",
        ),
    ] = None
    tau2_s: Annotated[Float, setting("thermal time constant of the rotor", "s", gt=0.0)] = 1200.0

    @model_validator(mode="after")
    def _resistances_stay_positive(self):
        for winding, alpha in (("1", self.alpha1_per_K), ("2", self.alpha2_per_K)):
            for key in ("theta_amb_C", "theta_init_C"):
                if not 1.0 + alpha * (getattr(self, key) - self.theta_ref_C) > 0.0:
                    raise ConfigError(
                        key,
                        f"gives R{winding} <= 0 (1 + alpha{winding}_per_K (theta - theta_ref_C) "
                        "must be > 0: a resistance is positive)",
                    )
        return self


@settings("plant.saturation")
class SaturationSettings:
    """Main-flux saturation of the plant (``[plant.saturation]``); the controller keeps its
    constant M̂, so saturation is also a model mismatch, unless ``[controller_model]`` gives it
    the curve (a commissioning's).

    The magnetising curve (:mod:`imdrive.kernels.machine`)::

        i_m = (psi_m / Lm0) (1 + (|psi_m| / psi_sat)^S),  Lm = Lm0 / (1 + (psi_m/psi_sat)^S)

    The paper gives no magnetising curve and none was measured for its 3 hp machine, so the
    default is a modelling choice, stated: the curve passes through the machine's ``M_H`` at
    its rated no-load flux, where the inductance has fallen to ``rated_ratio`` (0.9) of its
    unsaturated value, with ``S = 7``. Then ``Lm0 = M/rated_ratio`` and
    ``psi_sat = psi_rated (rated_ratio/(1 - rated_ratio))^(1/S)``; both can be set directly.
    """

    enabled: Annotated[Bool, setting("main-flux saturation on")] = False
    exponent: Annotated[
        Float,
        setting(
            "exponent S of the curve (> 0: i_m(psi_m) must be increasing, the curve monotone)",
            gt=0.0,
            le=50.0,
        ),
    ] = 7.0
    rated_ratio: Annotated[
        Float,
        setting(
            "Lm/Lm0 at the machine's rated no-load flux; with machine.M_H there it fixes Lm0 "
            "and psi_sat",
            gt=0.0,
            lt=1.0,
        ),
    ] = 0.9
    Lm0_H: Annotated[
        Float | None,
        setting("unsaturated magnetising inductance", "H", gt=0.0, derived=True),
    ] = None
    psi_sat_Wb: Annotated[
        Float | None,
        setting(
            "saturation flux of the curve",
            "Wb",
            gt=0.0,
            derived=True,
        ),
    ] = None

    def curve(self, machine) -> tuple[float, float, float]:
        """``(Lm0, psi_sat, S)`` of the magnetising curve ``Lm = Lm0/(1 + (psi_m/psi_sat)^S)``
        on ``machine`` (:class:`~imdrive.config.machine.MachineParams`): the given values, or
        the defaults through the machine's ``M_H`` at its rated flux (``Lm0 = M/rated_ratio``,
        ``psi_sat`` such that ``Lm(psi_rated) = M``)."""
        rho, S = self.rated_ratio, self.exponent
        Lm0 = self.Lm0_H if self.Lm0_H is not None else machine.M_H / rho
        psi_sat = self.psi_sat_Wb
        if psi_sat is None:
            psi_sat = machine.rated_flux_Wb * (rho / (1.0 - rho)) ** (1.0 / S)
        return Lm0, psi_sat, S


@settings("plant")
class PlantSettings:
    """Time-varying plant (section ``[plant]``): resistance changes, imposed speed."""

    R1_scale: Annotated[
        PositiveProfile,
        setting("multiplier of the plant's R1 (> 0): steps and ramps of stator resistance"),
    ] = C(1.0)
    R2_scale: Annotated[
        PositiveProfile,
        setting("multiplier of the plant's R2 (> 0): steps and ramps of rotor resistance"),
    ] = C(1.0)
    speed_mode: Annotated[
        Literal["dynamic", "imposed"],
        setting(
            '"dynamic": J dω/dt = Te − TL − Bω; "imposed": the speed follows imposed_speed_rpm'
        ),
    ] = "dynamic"
    imposed_speed_rpm: Annotated[
        Profile, setting('the rotor speed with speed_mode = "imposed"', "rpm")
    ] = C(0.0)
    thermal: Annotated[ThermalSettings, setting("first-order thermal model of each winding")] = (
        ThermalSettings()
    )
    saturation: Annotated[SaturationSettings, setting("main-flux saturation")] = (
        SaturationSettings()
    )


@settings("load")
class LoadSettings:
    """Load torque ``T_L = torque_Nm(t) + viscous_Nms ω + fan_Nms2 ω |ω|`` (``[load]``)."""

    torque_Nm: Annotated[Profile, setting("time-dependent load torque", "N m")] = C(0.0)
    torque_pu: Annotated[
        Profile | None,
        setting(
            "time-dependent load torque in per-unit of the machine's rated torque "
            "(config/rated.py), times in s (config/sequence.py); the per-unit twin of torque_Nm",
            default_doc="unset: torque_Nm",
        ),
    ] = None
    viscous_Nms: Annotated[
        Float,
        setting(
            "viscous load torque per unit speed, ·ω (>= 0: a passive load brakes, a negative "
            "one would drive the shaft from nothing)",
            "N m s/rad",
            ge=0.0,
        ),
    ] = 0.0
    fan_Nms2: Annotated[
        Float,
        setting("fan load torque, ·ω·|ω| (>= 0: a fan absorbs power)", "N m s²/rad²", ge=0.0),
    ] = 0.0
