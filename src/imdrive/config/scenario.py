"""Scenarios: a whole run described by frozen dataclasses, read from and written to TOML.

A scenario file has a table per section of :class:`Scenario` (``[machine]``, ``[plant]``,
``[plant.thermal]``, ``[control]``, ...; :data:`SECTIONS`), every key optional. The settings
classes below are the one description of those keys: their fields carry type, rule, default,
unit and meaning, from which validation, ``--set`` paths (:mod:`imdrive.config.overrides`),
``docs/scenarios.md`` and the JSON Schema (:mod:`imdrive.config.docs`) all follow.
``imdrive show PRESET`` prints complete examples.

Profiles are written as in :mod:`imdrive.config.profiles`. Unknown keys, wrong types and
values that break a rule raise :class:`~imdrive.errors.ConfigError` naming the field, whether
the scenario comes from a file (:meth:`Scenario.from_dict`) or is built in Python (the classes'
constructors, ``dataclasses.replace``).
"""

from __future__ import annotations

import dataclasses
import functools
import tomllib
import typing
from dataclasses import dataclass, fields, is_dataclass, replace
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import model_validator
from pydantic.fields import FieldInfo

from imdrive.config.inverter import InverterParams
from imdrive.config.machine import (
    MachineParams,
    machine_preset,
    machine_table,
    resolve_machine_file,
)
from imdrive.config.profiles import Profile
from imdrive.config.validation import (
    Bool,
    Float,
    Int,
    Name,
    ProfileValues,
    Str,
    setting,
    settings,
    validate,
)
from imdrive.errors import ConfigError

C = Profile.constant

PositiveProfile = Annotated[Profile, ProfileValues(gt=0.0)]
NonNegativeProfile = Annotated[Profile, ProfileValues(ge=0.0)]


@settings("plant.thermal")
class ThermalSettings:
    """First-order thermal model of each winding (section ``[plant.thermal]``).

    ``tau dtheta/dt = Rth P_cu - (theta - theta_amb)`` and ``R = R_ref (1 + alpha (theta -
    theta_ref))``, one per winding (1: stator, 2: rotor).
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
        Float, setting("thermal resistance, stator winding to ambient", "K/W", gt=0.0)
    ] = 0.4
    tau1_s: Annotated[Float, setting("thermal time constant of the stator", "s", gt=0.0)] = 1200.0
    Rth2_K_per_W: Annotated[
        Float, setting("thermal resistance, rotor winding to ambient", "K/W", gt=0.0)
    ] = 0.4
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
    constant M̂, so saturation is also a model mismatch.

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
        setting("unsaturated magnetising inductance", "H", gt=0.0, default_doc="M_H/rated_ratio"),
    ] = None
    psi_sat_Wb: Annotated[
        Float | None,
        setting(
            "saturation flux of the curve",
            "Wb",
            gt=0.0,
            default_doc="psi_rated (rated_ratio/(1 - rated_ratio))^(1/S)",
        ),
    ] = None


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


@settings("drive")
class DriveSettings:
    """Which controller drives the inverter (``[drive]``)."""

    mode: Annotated[
        Literal["open-loop", "vector"],
        setting(
            '"open-loop" (the default, so a file without [drive] runs the machine on the '
            "sinusoidal voltage of [open_loop] and ignores [control], [estimator], "
            '[compensator] and [injection]); "vector": field-oriented speed control ([control]) '
            "with its speed feedback, estimator and compensator. Every vector preset sets "
            '"vector"'
        ),
    ] = "open-loop"


@settings("open_loop")
class OpenLoopSettings:
    """Balanced sinusoidal voltage (``[open_loop]``); voltage is line-to-line rms."""

    voltage_V: Annotated[NonNegativeProfile, setting("line-to-line rms voltage (>= 0)", "V")] = C(
        220.0
    )
    frequency_Hz: Annotated[Profile, setting("supply frequency", "Hz")] = C(60.0)
    vf_ramp_s: Annotated[
        Float,
        setting(
            "V/f ramp from standstill to the (constant) voltage and frequency lasting this long; "
            "0: direct on line",
            "s",
            ge=0.0,
        ),
    ] = 0.0

    @model_validator(mode="after")
    def _ramp_needs_constant_targets(self):
        if self.vf_ramp_s > 0 and (
            len(self.voltage_V.points) != 1 or len(self.frequency_Hz.points) != 1
        ):
            raise ConfigError(
                "vf_ramp_s", "needs constant voltage_V and frequency_Hz (the ramp ends at them)"
            )
        return self


@settings("control")
class ControlSettings:
    """Indirect field-oriented speed control (``[control]``).

    PI gains not given are derived from the bandwidths (formulas in
    :mod:`imdrive.design.gains`).
    """

    speed_feedback: Annotated[
        Literal["measured", "mras", "reactive-mras", "afo", "ekf"],
        setting(
            '"measured": encoder speed; sensorless, the estimate of: "mras" Schauder\'s MRAS, '
            '"reactive-mras" the reactive-power MRAS, "afo" the adaptive full-order observer, '
            '"ekf" the extended Kalman filter (docs/estimators.md)'
        ),
    ] = "measured"
    speed_ref_rpm: Annotated[Profile, setting("speed reference", "rpm")] = C(0.0)
    flux_ref_Wb: Annotated[
        PositiveProfile | None,
        setting(
            "rotor-flux reference (> 0)",
            "Wb",
            default_doc="the machine's rated flux ({rated_flux_Wb} Wb for {preset})",
        ),
    ] = None
    speed_bandwidth_Hz: Annotated[
        Float, setting("speed-loop bandwidth the speed PI gains are derived from", "Hz", gt=0.0)
    ] = 5.0
    current_bandwidth_Hz: Annotated[
        Float,
        setting("current-loop bandwidth the current PI gains are derived from", "Hz", gt=0.0),
    ] = 200.0
    speed_kp: Annotated[
        Float | None,
        setting(
            "speed PI proportional gain (> 0: a negative gain is positive feedback, never a "
            "controller)",
            "A/(rad/s)",
            gt=0.0,
            default_doc="from speed_bandwidth_Hz",
        ),
    ] = None
    speed_ki: Annotated[
        Float | None,
        setting(
            "speed PI integral gain (>= 0: a negative one integrates the error the wrong way)",
            "A/rad",
            ge=0.0,
            default_doc="from speed_bandwidth_Hz",
        ),
    ] = None
    current_kp: Annotated[
        Float | None,
        setting(
            "current PI proportional gain (> 0: a negative one is positive feedback)",
            "V/A",
            gt=0.0,
            default_doc="from current_bandwidth_Hz",
        ),
    ] = None
    current_ki: Annotated[
        Float | None,
        setting(
            "current PI integral gain (>= 0: a negative one integrates the error the wrong way)",
            "V/(A s)",
            ge=0.0,
            default_doc="from current_bandwidth_Hz",
        ),
    ] = None
    current_limit_A: Annotated[
        Float | None,
        setting(
            "stator current limit (peak)",
            "A",
            gt=0.0,
            default_doc="2 × the rated peak current ({current_limit_A} A for {preset})",
        ),
    ] = None
    decoupling: Annotated[
        Bool, setting("cross-coupling and back-emf feed-forward in the current controllers")
    ] = True
    field_weakening: Annotated[
        Bool,
        setting(
            "field weakening above base speed: the flux reference is scaled down by a voltage "
            "feedback that holds the voltage use at field_weakening_voltage "
            "(kernels/ifoc.py, field_weakening); turns injection.headroom on"
        ),
    ] = False
    field_weakening_voltage: Annotated[
        Float,
        setting("field weakening: voltage use it holds (fraction of Vdc/√3)", gt=0.0, le=1.0),
    ] = 0.9
    field_weakening_rate: Annotated[
        Float,
        setting("field weakening: integral gain of the flux factor", "1/s", gt=0.0),
    ] = 20.0
    field_weakening_min: Annotated[
        Float, setting("field weakening: lowest flux factor", gt=0.0, le=1.0)
    ] = 0.2
    dead_time_compensation: Annotated[
        Literal["none", "feedforward"],
        setting(
            '"feedforward": add sgn(i) t_d f_sw Vdc_meas to each phase voltage reference '
            "(measured current, smooth over inverter.sign_band_A)"
        ),
    ] = "none"
    dead_time_compensation_s: Annotated[
        Float | None,
        setting(
            "the dead time the compensation assumes",
            "s",
            ge=0.0,
            default_doc="inverter.dead_time_s (perfect knowledge)",
        ),
    ] = None
    delay_periods: Annotated[
        Int,
        setting(
            "computation delay: 0, or 1 (the reference computed at sample k acts over the next "
            "period, as on a DSP)",
            ge=0,
            le=1,
        ),
    ] = 0
    delay_compensation: Annotated[
        Bool,
        setting(
            "advance the dq-to-alpha-beta angle by the delay (1.5 Ts instead of 0.5 Ts with "
            "delay_periods = 1)"
        ),
    ] = True


@settings("estimator")
class EstimatorSettings:
    """The controller's and estimator's machine model (``[estimator]``); unset: the plant's."""

    R1_ohm: Annotated[
        Float | None, setting("stator resistance", "ohm", gt=0.0, default_doc="the plant's")
    ] = None
    R2_ohm: Annotated[
        Float | None,
        setting(
            "rotor resistance: the initial estimate R̂2", "ohm", gt=0.0, default_doc="the plant's"
        ),
    ] = None
    Ll1_H: Annotated[
        Float | None, setting("stator leakage inductance", "H", gt=0.0, default_doc="the plant's")
    ] = None
    Ll2_H: Annotated[
        Float | None, setting("rotor leakage inductance", "H", gt=0.0, default_doc="the plant's")
    ] = None
    M_H: Annotated[
        Float | None,
        setting("magnetising inductance", "H", gt=0.0, default_doc="the plant's"),
    ] = None
    R2_adaptation: Annotated[
        Literal["compensator", "afo", "ekf"],
        setting(
            'who adapts R̂2: "compensator" the [compensator] section (the fuzzy compensator on '
            'the MRAS, or its injection variant; off unless compensator.enabled), "afo" the '
            'full-order observer\'s law (needs control.speed_feedback = "afo"), "ekf" the '
            'EKF\'s R2 state (needs "ekf")'
        ),
    ] = "compensator"


@settings("reactive_mras")
class ReactiveMrasSettings:
    """Reactive-power MRAS speed estimator (``[reactive_mras]``, Peng & Fukao 1994).

    ``K1``, ``K2`` default from ``bandwidth_Hz``
    (:func:`imdrive.design.estimators.default_reactive_mras_gains`).
    """

    bandwidth_Hz: Annotated[
        Float, setting("bandwidth K1 and K2 are derived from", "Hz", gt=0.0)
    ] = 20.0
    K1: Annotated[
        Float | None,
        setting(
            "adaptation PI proportional gain", "(rad/s)/(A V)", default_doc="from bandwidth_Hz"
        ),
    ] = None
    K2: Annotated[
        Float | None,
        setting("adaptation PI integral gain", "(rad/s²)/(A V)", default_doc="from bandwidth_Hz"),
    ] = None


@settings("afo")
class AfoSettings:
    """Adaptive full-order flux observer (``[afo]``, Kubota, Matsuse & Nakano 1993).

    Gains default from the bandwidths (:mod:`imdrive.design.estimators`).
    """

    gain: Annotated[
        Literal["regeneration", "fixed"],
        setting(
            'observer gain: "regeneration" g2 = -rho (R̂1 + σL1 g1) L2/M, for stable '
            'low-speed regeneration; "fixed" g1, g2 as given (g1 = g2 = 0: the plain observer)'
        ),
    ] = "regeneration"
    rho: Annotated[
        Float,
        setting(
            "share of the regeneration gain (1: no unstable band but an undamped flux mode at "
            "zero stator frequency)",
            ge=0.0,
            le=1.0,
        ),
    ] = 0.9
    g1_per_s: Annotated[Float, setting("current-equation gain g1", "1/s", ge=0.0)] = 0.0
    g2_ohm: Annotated[Float, setting('flux-equation gain g2 (gain = "fixed")', "ohm")] = 0.0
    bandwidth_Hz: Annotated[
        Float, setting("speed-adaptation bandwidth Kp, Ki are derived from", "Hz", gt=0.0)
    ] = 40.0
    Kp: Annotated[
        Float | None,
        setting(
            "speed adaptation proportional gain", "(rad/s)/(A Wb)", default_doc="from bandwidth_Hz"
        ),
    ] = None
    Ki: Annotated[
        Float | None,
        setting(
            "speed adaptation integral gain", "(rad/s²)/(A Wb)", default_doc="from bandwidth_Hz"
        ),
    ] = None
    R1_adaptation: Annotated[Bool, setting("adapt R̂1 (Kubota et al. 1993)")] = False
    R1_bandwidth_rad_s: Annotated[
        Float, setting("R̂1 adaptation rate the gain is derived from", "rad/s", gt=0.0)
    ] = 2.0
    R2_bandwidth_rad_s: Annotated[
        Float,
        setting(
            'R̂2 adaptation rate (estimator.R2_adaptation = "afo"; needs [flux_injection])',
            "rad/s",
            gt=0.0,
        ),
    ] = 2.0


@settings("ekf")
class EkfSettings:
    """Extended Kalman filter for speed and R2 (``[ekf]``); noise as standard deviations.

    Per-period variances: currents ``(voltage_noise_V Ts / σL1)²``, fluxes
    ``(flux_noise_Wb_per_s Ts)²``... see :func:`imdrive.design.estimators.default_ekf_noise`.
    """

    voltage_noise_V: Annotated[
        Float, setting("voltage uncertainty behind the current's process noise", "V", gt=0.0)
    ] = 5.0
    flux_noise_Wb_per_s: Annotated[
        Float, setting("rotor-flux process noise density", "Wb/s", gt=0.0)
    ] = 0.1
    acceleration_noise_rad_s2: Annotated[
        Float, setting("speed process noise: electrical acceleration uncertainty", "rad/s²", gt=0.0)
    ] = 2000.0
    R2_drift_ohm_per_s: Annotated[
        Float, setting("R2 process noise: drift-rate uncertainty", "ohm/s", gt=0.0)
    ] = 0.5
    current_noise_A: Annotated[
        Float, setting("measurement noise per current component (rms)", "A", gt=0.0)
    ] = 0.05


@settings("flux_injection")
class FluxInjectionSettings:
    """A sinusoid on the rotor-flux command (``[flux_injection]``), the excitation under which
    R2 and the speed are estimated together (Kubota & Matsuse 1994); 0 = off."""

    amplitude: Annotated[
        Float, setting("relative amplitude of the sinusoid on the flux command", ge=0.0, lt=1.0)
    ] = 0.0
    frequency_Hz: Annotated[Float, setting("frequency of the sinusoid", "Hz", gt=0.0)] = 2.0


@settings("mras")
class MrasSettings:
    """Schauder's MRAS speed estimator (``[mras]``).

    ``K1``, ``K2`` default from ``bandwidth_Hz`` (:func:`imdrive.design.gains.default_mras_gains`).
    """

    wc_rad_s: Annotated[
        Float,
        setting(
            "cut-off of the 1/(s + ωc) replacement of the reference model's pure integrator "
            "(0: pure integrator; default derived from the stability maps, docs/stability.md)",
            "rad/s",
            ge=0.0,
        ),
    ] = 15.0
    bandwidth_Hz: Annotated[
        Float,
        setting("bandwidth K1 and K2 are derived from (default: docs/stability.md)", "Hz", gt=0.0),
    ] = 20.0
    K1: Annotated[
        Float | None,
        setting(
            "adaptation PI proportional gain (>= 0: Popov's hyperstability proof needs "
            "non-negative gains)",
            "(rad/s)/Wb²",
            ge=0.0,
            default_doc="from bandwidth_Hz",
        ),
    ] = None
    K2: Annotated[
        Float | None,
        setting(
            "adaptation PI integral gain (> 0: the integral makes the estimate track; a "
            "negative one drives it away)",
            "(rad/s²)/Wb²",
            gt=0.0,
            default_doc="from bandwidth_Hz",
        ),
    ] = None
    R1_rate_per_s: Annotated[
        Float,
        setting(
            "online R1 estimation beside the MRAS: convergence rate (0: off; "
            "kernels/estimators/mras.py)",
            "1/s",
            ge=0.0,
        ),
    ] = 0.0
    normalise: Annotated[
        Bool | None,
        setting(
            "scale the adaptation error by (design flux / estimated flux)², so the loop keeps "
            "its bandwidth in field weakening (kernels/estimators/mras.py)",
            default_doc="on with control.field_weakening, else off",
        ),
    ] = None
    R1_standstill: Annotated[
        Bool,
        setting(
            "standstill R1 identification: while the speed reference is zero and the flux "
            "current flows, R̂1 = Σ v·i / Σ |i|² over the part after four rotor time constants, "
            "applied when the reference leaves zero (kernels/estimators/mras.py); exact on "
            "the average inverter, biased by an uncompensated dead-time voltage (1.9 R1 on "
            "sensorless-realistic): leave it off there"
        ),
    ] = False
    R1_max_freq_Hz: Annotated[
        Float,
        setting(
            "online R1 estimation runs below this stator frequency (and in motoring only)",
            "Hz",
            gt=0.0,
        ),
    ] = 30.0


@settings("compensator")
class CompensatorSettings:
    """The fuzzy rotor-resistance compensator (``[compensator]``, paper §4).

    ``gain_E_per_Wb`` and ``gain_DE_per_Wb`` scale e_d0 and its change per period before the
    quantiser (thresholds 0.25 ... 5): 1e6 reproduces the paper's micro-weber thresholds.
    ``G_CR_ohm`` is the change of R2_hat per output level and period. The clamps default to
    0.5 and 2 times the initial estimate. ``period_s`` defaults to 10 ms, or to one injection
    period with ``input = "demodulated"``.
    """

    enabled: Annotated[Bool, setting("run the fuzzy R2 compensator")] = False
    t_on_s: Annotated[Float, setting("time the compensator starts", "s", ge=0.0)] = 0.0
    period_s: Annotated[
        Float | None,
        setting(
            "decision period",
            "s",
            gt=0.0,
            default_doc='0.01; one injection period with input = "demodulated"',
        ),
    ] = None
    gain_E_per_Wb: Annotated[
        Float,
        setting(
            "scaling of e_d0 before the 13-level quantiser (1e6: the paper's µWb thresholds)",
            "1/Wb",
            gt=0.0,
        ),
    ] = 1e6
    gain_DE_per_Wb: Annotated[
        Float,
        setting("scaling of the change of e_d0 per period before the quantiser", "1/Wb", gt=0.0),
    ] = 1e6
    G_CR_ohm: Annotated[
        Float, setting("change of R̂2 per output level and period", "ohm", ge=0.0)
    ] = 0.001
    R2_min_ohm: Annotated[
        Float | None,
        setting("lower clamp of R̂2", "ohm", gt=0.0, default_doc="0.5 × the initial R̂2"),
    ] = None
    R2_max_ohm: Annotated[
        Float | None,
        setting("upper clamp of R̂2", "ohm", gt=0.0, default_doc="2 × the initial R̂2"),
    ] = None
    table: Annotated[
        Literal["paper", "rules"],
        setting('"paper": the printed Table III; "rules": compiled from the fitted rule base'),
    ] = "paper"
    input: Annotated[
        Literal["e_d0", "demodulated"],
        setting(
            '"e_d0": the paper\'s input; "demodulated": e_d0 detected synchronously with the '
            "injection ([injection])"
        ),
    ] = "e_d0"
    average: Annotated[
        Bool, setting("the input is its mean over the period, not a sample at its end")
    ] = True
    gating: Annotated[
        Bool | None,
        setting(
            "freeze R̂2 during speed and load transients and in voltage saturation, and move "
            "the injection frequency away from the stator frequency (kernels/compensator.py)",
            default_doc='on with input = "demodulated", off with "e_d0"',
        ),
    ] = None
    gate_speed_rpm: Annotated[
        Float,
        setting(
            "gating: speed-reference change within a period, or mean speed error over it, "
            "above which the period is a transient",
            "rpm",
            gt=0.0,
        ),
    ] = 1.0
    gate_iq_A: Annotated[
        Float,
        setting(
            "gating: change of the period-mean iq* from one period to the next above which the "
            "period is a load transient",
            "A",
            gt=0.0,
        ),
    ] = 0.3
    gate_voltage: Annotated[
        Float,
        setting(
            "gating: voltage use (fraction of Vdc/√3) from which the period counts as saturated",
            gt=0.0,
        ),
    ] = 0.97
    gate_band_Hz: Annotated[
        Float,
        setting(
            "gating: the injection frequency is switched when |stator frequency| is within this "
            "of it (0: never)",
            "Hz",
            ge=0.0,
        ),
    ] = 1.0
    gate_hold_periods: Annotated[
        Int, setting("gating: decisions still skipped after a gated one", ge=0)
    ] = 1
    step_law: Annotated[
        Literal["table", "adaptive"],
        setting(
            '"table": R̂2 changes by G_CR_ohm × the table\'s level (the paper); "adaptive": '
            "inside the first threshold a continuous level fine_gain × (scaled E) and an "
            "integrated drift rate, for fine and ramp-following adaptation "
            "(kernels/compensator.py)"
        ),
    ] = "table"
    fine_gain: Annotated[
        Float,
        setting(
            'step_law = "adaptive": level per unit of scaled E inside the first threshold', gt=0.0
        ),
    ] = 2.5
    drift_gain: Annotated[
        Float,
        setting(
            'step_law = "adaptive": share of each fine step added to the drift rate (0: none)',
            ge=0.0,
        ),
    ] = 0.3
    drift_min_freq_Hz: Annotated[
        Float | None,
        setting(
            'step_law = "adaptive" with gating: the drift term is integrated only where the '
            "mean stator frequency is above this, and reset below it (kernels/compensator.py)",
            "Hz",
            ge=0.0,
            default_doc="the higher injection frequency (0 without injection)",
        ),
    ] = None
    drift_max_ohm: Annotated[
        Float | None,
        setting(
            'step_law = "adaptive": bound of the drift rate, per decision period',
            "ohm",
            ge=0.0,
            default_doc="3 × G_CR_ohm",
        ),
    ] = None

    @model_validator(mode="after")
    def _clamps_in_order(self):
        lo, hi = self.R2_min_ohm, self.R2_max_ohm
        if lo is not None and hi is not None and not lo < hi:
            raise ConfigError("R2_min_ohm", "must be < compensator.R2_max_ohm")
        return self


@settings("injection")
class InjectionSettings:
    """Persistent excitation (``[injection]``): a sinusoid added to the flux-current reference.

    R2 identification from a low-frequency AC flux component is Kubota & Matsuse (IEEE Trans.
    Ind. Appl. 30(5), 1994); feeding its demodulated flux error to the paper's table is ours.

    ``amplitude_A`` = 0 switches it off. The compensator's ``input = "demodulated"`` feeds on
    e_d0 detected synchronously with this sinusoid; its period should be a whole number of
    injection periods (the default compensator period for that input is one).
    """

    amplitude_A: Annotated[
        Float, setting("amplitude of the sinusoid added to id* (0: off)", "A", ge=0.0)
    ] = 0.0
    frequency_Hz: Annotated[Float, setting("frequency of the sinusoid", "Hz", gt=0.0)] = 2.0
    frequency2_Hz: Annotated[
        Float | None,
        setting(
            "the alternative frequency the gating switches to near the stator frequency; "
            "the compensator period must hold whole periods of both",
            "Hz",
            gt=0.0,
            default_doc="2 × frequency_Hz",
        ),
    ] = None
    frequency3_Hz: Annotated[
        Float | None,
        setting(
            "a third frequency for the gating's schedule: the lowest of the three at least "
            "compensator.gate_band_Hz from the stator frequency is used (kernels/compensator.py); "
            "the compensator period must hold whole periods of it",
            "Hz",
            gt=0.0,
            default_doc="none: the two-frequency schedule",
        ),
    ] = None
    headroom: Annotated[
        Bool | None,
        setting(
            "the amplitude backs off as the voltage use (peak over each injection period) "
            "rises from headroom_from to headroom_to, and is off in field weakening; the "
            "compensator freezes below half amplitude (kernels/compensator.py)",
            default_doc="on with control.field_weakening, else off",
        ),
    ] = None
    headroom_from: Annotated[
        Float, setting("headroom: voltage use where the amplitude starts to fall", gt=0.0)
    ] = 0.85
    headroom_to: Annotated[
        Float, setting("headroom: voltage use where it reaches zero", gt=0.0)
    ] = 0.95
    t_on_s: Annotated[Float, setting("time the injection starts", "s", ge=0.0)] = 0.0
    compensate_filter: Annotated[
        Bool,
        setting(
            "filter-compensated detection: undo the MRAS's s/(s + ωc) comparison filter at the "
            "injection's two side bands (kernels/compensator.py), which rotates the detected "
            "signal at low stator frequency; false: plain 2 e_d0 sin detection"
        ),
    ] = False
    lowpass_rad_s: Annotated[
        Float,
        setting(
            "optional low-pass of the detected product, for display (0: none)", "rad/s", ge=0.0
        ),
    ] = 0.0


@settings("sensor")
class SensorSettings:
    """Sensor imperfections (``[sensor]``).

    Two phase-current sensors (a and b; ``i_c = -i_a - i_b``), each with gain, offset, Gaussian
    noise (seeded) and ADC quantisation, plus the DC-link voltage sensor's gain; and the 0.1
    offsets of the α/β current. Models in :mod:`imdrive.kernels.sensors`.
    """

    i_offset_alpha_A: Annotated[Float, setting("DC offset of the measured α current", "A")] = 0.0
    i_offset_beta_A: Annotated[Float, setting("DC offset of the measured β current", "A")] = 0.0
    gain_a: Annotated[Float, setting("gain of the phase-a current sensor", gt=0.0)] = 1.0
    gain_b: Annotated[Float, setting("gain of the phase-b current sensor", gt=0.0)] = 1.0
    offset_a_A: Annotated[Float, setting("offset of the phase-a current sensor", "A")] = 0.0
    offset_b_A: Annotated[Float, setting("offset of the phase-b current sensor", "A")] = 0.0
    noise_rms_A: Annotated[
        Float, setting("rms of the Gaussian noise of each current sensor", "A", ge=0.0)
    ] = 0.0
    adc_bits: Annotated[
        Int | None,
        setting("ADC resolution of the current sensors", "bit", ge=2, le=32, default_doc="none"),
    ] = None
    adc_range_A: Annotated[
        Float, setting("ADC full scale of the current sensors (±)", "A", gt=0.0)
    ] = 50.0
    seed: Annotated[
        Int,
        setting(
            "seed of the sensor noise (same seed, same run; a 63-bit integer)",
            ge=0,
            le=2**63 - 1,
        ),
    ] = 0
    vdc_gain: Annotated[
        Float,
        setting(
            "gain of the DC-link voltage sensor: the controller turns volts into duty cycles "
            "with gain × Vdc",
            gt=0.0,
        ),
    ] = 1.0

    @property
    def per_phase(self) -> bool:
        """Whether the per-phase current-sensor model is needed (anything not ideal)."""
        return (
            self.gain_a != 1.0
            or self.gain_b != 1.0
            or self.offset_a_A != 0.0
            or self.offset_b_A != 0.0
            or self.noise_rms_A != 0.0
            or self.adc_bits is not None
        )


#: slowest default logging rate, Hz (see :func:`default_log_every`)
DEFAULT_LOG_RATE_HZ = 1000.0


def default_log_every(Ts_s: float) -> int:
    """The default logging decimation: the most control periods per logged row that keep the
    log at >= :data:`DEFAULT_LOG_RATE_HZ` (10 at Ts = 100 µs; 1 for Ts >= 1 ms).

    Parameters
    ----------
    Ts_s : float
        Control period, s.

    Returns
    -------
    int
        ``max(1, floor(1 / (DEFAULT_LOG_RATE_HZ Ts_s)))``, at most 2e9.
    """
    # the small tolerance keeps 1e-3 / 1e-4 (= 9.999999999999998) at 10
    n = int((1.0 / (DEFAULT_LOG_RATE_HZ * Ts_s)) * (1.0 + 1e-9))
    return min(max(n, 1), 2_000_000_000)


@settings("simulation")
class SimulationSettings:
    """Integration and logging (``[simulation]``)."""

    t_end_s: Annotated[Float, setting("run length", "s", gt=0.0)] = 1.0
    Ts_s: Annotated[Float, setting("control period (sampling and PWM period)", "s", gt=0.0)] = (
        100e-6
    )
    substeps: Annotated[
        Int,
        setting(
            "RK4 steps of the plant per control period (<= 1000: beyond, the step is far below "
            "any time constant of the machine and the run only gets slower)",
            ge=1,
            le=1000,
        ),
    ] = 1
    log_every: Annotated[
        Int | None,
        setting(
            "logging decimation: one row of timeseries every this many control periods "
            "(<= 2e9, the most periods a run may have; 1: every period). The default keeps "
            "logging at >= 1 kHz, which resolves everything up to the current loop (its "
            "bandwidth is a few hundred Hz) and the stator frequency; report.html is "
            "min/max-decimated anyway. It is fixed when the scenario is read (summary.json "
            "records the number); Scenario.with_overrides derives the default again for a new "
            "Ts_s",
            ge=1,
            le=2_000_000_000,
            default_doc="max(1, floor(1 ms / Ts_s)): 10 at the default Ts_s = 100 µs",
        ),
    ] = None
    divergence_current_A: Annotated[
        Float | None,
        setting(
            "current magnitude that stops a diverging run",
            "A",
            gt=0.0,
            default_doc="100 × the rated peak current ({divergence_current_A} A for {preset})",
        ),
    ] = None
    divergence_speed_rpm: Annotated[
        Float, setting("speed magnitude that stops a diverging run", "rpm", gt=0.0)
    ] = 20000.0
    lost_control_rpm: Annotated[
        Float,
        setting(
            "loss of control: the actual speed departs from its reference by more than this "
            "(vector control, free speed; 0: not checked)",
            "rpm",
            ge=0.0,
        ),
    ] = 200.0
    lost_control_s: Annotated[
        Float,
        setting("... for at least this long without interruption", "s", gt=0.0),
    ] = 1.0

    @model_validator(mode="after")
    def _period_fits_run(self):
        if self.Ts_s > self.t_end_s:
            raise ConfigError("Ts_s", "must be <= simulation.t_end_s")
        if self.t_end_s / self.Ts_s > 2e9:
            raise ConfigError("Ts_s", "gives more than 2e9 periods")
        if self.log_every is None:
            # frozen dataclass: set once here, so every consumer sees an int; the mark lets
            # Scenario.with_overrides derive it again when Ts_s changes
            object.__setattr__(self, "log_every", default_log_every(self.Ts_s))
            object.__setattr__(self, "_log_every_auto", True)
        return self

    @property
    def n_steps(self) -> int:
        return int(round(self.t_end_s / self.Ts_s))


@settings("output")
class OutputSettings:
    """What ``imdrive run`` writes besides summary.json (``[output]``)."""

    figures: Annotated[Bool, setting("write the PNG figures")] = True
    csv: Annotated[
        Bool,
        setting(
            "write timeseries.csv (text, 9 significant digits; about 0.4 MB per simulated "
            "second of a vector drive at the default 1 kHz logging, 4 MB at log_every = 1: for "
            "long or full-rate runs prefer parquet = true, csv = false)"
        ),
    ] = True
    report: Annotated[
        Bool,
        setting(
            "write report.html: interactive linked plots, the summary and the scenario in one "
            "self-contained file that works offline"
        ),
    ] = True
    mat: Annotated[
        Bool, setting("write timeseries.mat (MATLAB; one vector per column, a units struct)")
    ] = False
    parquet: Annotated[
        Bool,
        setting(
            "write timeseries.parquet, the format for big runs: exact float64 (the CSV rounds "
            "to 9 digits), zstd-compressed, read about 2-3 times faster than the CSV and a third "
            "smaller (pandas.read_parquet; units in the schema metadata)"
        ),
    ] = False


SECTIONS: dict[str, type] = {
    "plant": PlantSettings,
    "load": LoadSettings,
    "inverter": InverterParams,
    "drive": DriveSettings,
    "open_loop": OpenLoopSettings,
    "control": ControlSettings,
    "estimator": EstimatorSettings,
    "mras": MrasSettings,
    "reactive_mras": ReactiveMrasSettings,
    "afo": AfoSettings,
    "ekf": EkfSettings,
    "flux_injection": FluxInjectionSettings,
    "compensator": CompensatorSettings,
    "injection": InjectionSettings,
    "sensor": SensorSettings,
    "simulation": SimulationSettings,
    "output": OutputSettings,
}

DEFAULT_MACHINE_PRESET = "paper-table-iv"


@settings("")
class Scenario:
    """A complete run: machine, inverter, drive, profiles, simulation settings, outputs.

    Built from a TOML-shaped dictionary by :meth:`from_dict` (the ``[machine]`` table holds
    ``preset`` and the fields that override it), or directly from the section objects.
    Every key, its unit and its default: ``docs/scenarios.md``.

    Attributes
    ----------
    name, description : str
        Name of the run (the default output folder is ``out/NAME``) and free text.
    machine : MachineParams
        The plant's machine.
    machine_preset : str
        The published parameter set the machine starts from (``machine.preset`` in a file).
    plant, load, inverter, drive, open_loop, control : settings section
        Time-varying plant, load torque, DC-link inverter, which controller drives it,
        open-loop voltage, field-oriented speed control.
    estimator, mras, reactive_mras, afo, ekf : settings section
        The controller's machine model and the speed estimators' settings.
    flux_injection, compensator, injection : settings section
        Sinusoid on the flux command, the fuzzy R2 compensator, persistent excitation.
    sensor, simulation, output : settings section
        Current-sensor imperfections, integration and logging, the files ``imdrive run``
        writes.
    """

    name: Annotated[
        Name,
        setting(
            "name of the run; the default output folder is out/NAME, so 1-100 characters "
            "from A-Z a-z 0-9 . _ + -, starting with a letter or digit"
        ),
    ] = "scenario"
    description: Annotated[Str, setting("free text")] = ""
    machine: Annotated[MachineParams, setting("the plant's machine")] = machine_preset(
        DEFAULT_MACHINE_PRESET
    )
    machine_preset: Annotated[
        Str,
        setting(
            "the published parameter set the machine starts from (in a file: machine.preset); "
            "the other [machine] keys override its values"
        ),
    ] = DEFAULT_MACHINE_PRESET
    plant: Annotated[PlantSettings, setting("time-varying plant")] = PlantSettings()
    load: Annotated[LoadSettings, setting("load torque")] = LoadSettings()
    inverter: Annotated[InverterParams, setting("DC-link inverter")] = InverterParams()
    drive: Annotated[DriveSettings, setting("which controller drives the inverter")] = (
        DriveSettings()
    )
    open_loop: Annotated[OpenLoopSettings, setting("open-loop sinusoidal voltage")] = (
        OpenLoopSettings()
    )
    control: Annotated[ControlSettings, setting("field-oriented speed control")] = ControlSettings()
    estimator: Annotated[EstimatorSettings, setting("the controller's machine model")] = (
        EstimatorSettings()
    )
    mras: Annotated[MrasSettings, setting("Schauder's MRAS speed estimator")] = MrasSettings()
    reactive_mras: Annotated[
        ReactiveMrasSettings, setting("reactive-power MRAS speed estimator")
    ] = ReactiveMrasSettings()
    afo: Annotated[AfoSettings, setting("adaptive full-order flux observer")] = AfoSettings()
    ekf: Annotated[EkfSettings, setting("extended Kalman filter for speed and R2")] = EkfSettings()
    flux_injection: Annotated[FluxInjectionSettings, setting("sinusoid on the flux command")] = (
        FluxInjectionSettings()
    )
    compensator: Annotated[
        CompensatorSettings, setting("the fuzzy rotor-resistance compensator")
    ] = CompensatorSettings()
    injection: Annotated[InjectionSettings, setting("persistent excitation")] = InjectionSettings()
    sensor: Annotated[SensorSettings, setting("current-sensor imperfections")] = SensorSettings()
    simulation: Annotated[SimulationSettings, setting("integration and logging")] = (
        SimulationSettings()
    )
    output: Annotated[OutputSettings, setting("files imdrive run writes")] = OutputSettings()

    @model_validator(mode="before")
    @classmethod
    def _machine_table(cls, data):
        """The file form: ``[machine]`` is a preset name plus the fields that override it."""
        if not isinstance(data, dict):
            return data  # direct construction: the objects themselves
        if "machine_preset" in data:
            raise ConfigError("machine_preset", "unknown key")
        if "machine" not in data or isinstance(data["machine"], MachineParams):
            return data
        table = data["machine"]
        if not isinstance(table, dict):
            raise ConfigError("machine", "must be a table")
        table = dict(table)
        preset = table.pop("preset", DEFAULT_MACHINE_PRESET)
        if not isinstance(preset, str):
            raise ConfigError("machine.preset", f"must be a string, got {preset!r}")
        data = dict(data)
        data["machine"] = machine_table(preset, table)  # preset < its file < this table
        data["machine_preset"] = preset
        return data

    @model_validator(mode="after")
    def _joint_rules(self):
        """Rules between sections, checked on the final scenario."""
        inv = self.inverter
        if inv.model == "switching":
            f_Ts = inv.switching_frequency_Hz * self.simulation.Ts_s
            if abs(f_Ts - 1.0) > 1e-9:
                raise ConfigError(
                    "simulation.Ts_s",
                    f"must be 1/inverter.switching_frequency_Hz = "
                    f"{1.0 / inv.switching_frequency_Hz:g} s with the switching model (one "
                    f"carrier period per control period; got {self.simulation.Ts_s:g})",
                )
        fb = self.control.speed_feedback
        if fb not in ("measured", "mras") and (
            self.compensator.enabled or self.injection.amplitude_A != 0.0
        ):
            raise ConfigError(
                "control.speed_feedback",
                f'"{fb}" gives no flux error e_d0: the compensator and the injection need '
                '"mras" or "measured"',
            )
        r2a = self.estimator.R2_adaptation
        if r2a != "compensator":
            if fb != r2a:
                raise ConfigError(
                    "estimator.R2_adaptation",
                    f'"{r2a}" needs control.speed_feedback = "{r2a}" (got "{fb}")',
                )
        t_dc = self.control.dead_time_compensation_s
        if t_dc is not None and not t_dc < 0.5 / inv.switching_frequency_Hz:
            raise ConfigError(
                "control.dead_time_compensation_s",
                "must be < half a switching period, 0.5/inverter.switching_frequency_Hz",
            )
        self._compensator_rules()
        return self

    def _compensator_rules(self) -> None:
        """The R̂2 clamps in order, given or default (one given clamp against the other's
        default: ``R2_min_ohm`` above the default ``R2_max_ohm`` made R̂2 jump); the decision
        period and the injection against the run and the machine."""
        comp = self.compensator
        R2h = self.estimator.R2_ohm if self.estimator.R2_ohm is not None else self.machine.R2_ohm
        lo = comp.R2_min_ohm if comp.R2_min_ohm is not None else 0.5 * R2h
        hi = comp.R2_max_ohm if comp.R2_max_ohm is not None else 2.0 * R2h
        if not lo < hi:
            field = (
                "compensator.R2_min_ohm"
                if comp.R2_min_ohm is not None
                else ("compensator.R2_max_ohm")
            )
            raise ConfigError(
                field,
                f"the clamps of R̂2 must satisfy R2_min_ohm < R2_max_ohm (got {lo:g} >= {hi:g}; "
                f"an unset clamp is 0.5 or 2 × the initial R̂2 = {R2h:g} ohm)",
            )
        Ts = self.simulation.Ts_s
        if comp.period_s is not None and comp.period_s / Ts > 2e9:
            raise ConfigError("compensator.period_s", "is more than 2e9 control periods")
        inj = self.injection
        if 1.0 / (inj.frequency_Hz * Ts) > 2e9:
            raise ConfigError("injection.frequency_Hz", "has a period of more than 2e9 periods")
        i_rated = self.machine.rated_current_A
        if inj.amplitude_A > i_rated:
            raise ConfigError(
                "injection.amplitude_A",
                f"must be <= the machine's rated peak current {i_rated:.3g} A (a persistent "
                f"excitation is a small perturbation of the flux current; got {inj.amplitude_A:g})",
            )

    # -- construction ----------------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: dict) -> Scenario:
        """Build and validate a scenario from its TOML-shaped dictionary.

        Parameters
        ----------
        data : dict
            The scenario file's tables, as ``tomllib`` reads them.

        Returns
        -------
        Scenario
            The validated scenario.
        """
        if not isinstance(data, dict):
            raise ConfigError("scenario", "must be a table")
        return validate(cls, data)

    @classmethod
    def from_toml(
        cls, text: str, overrides: list[str] | tuple[str, ...] = (), *, base_dir=None
    ) -> Scenario:
        """Parse TOML text, apply ``key.path=value`` overrides, validate.

        Parameters
        ----------
        text : str
            A scenario file's text.
        overrides : list of str
            ``key.path=value`` strings (values parsed as TOML), applied in order.
        base_dir : str or pathlib.Path, optional
            The folder a relative ``[machine] file`` of ``text`` is read from (the scenario
            file's); default the working directory, as for an override's.

        Returns
        -------
        Scenario
            The validated scenario.
        """
        _check_override_list(overrides)
        try:
            data = tomllib.loads(text.removeprefix("\ufeff"))  # a UTF-8 byte-order mark
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError("scenario", f"invalid TOML: {exc}") from None
        resolve_machine_file(data, base_dir)
        for ov in overrides:
            apply_override(data, ov)
        return cls.from_dict(data)

    @classmethod
    def read(cls, preset_or_path: str, overrides: list[str] | tuple[str, ...] = ()) -> Scenario:
        """A built-in preset by name, or a scenario file by path.

        Parameters
        ----------
        preset_or_path : str or pathlib.Path
            A preset name (``imdrive presets``), a TOML scenario file, or a run's
            ``summary.json`` (its ``"scenario"``, to run it again).
        overrides : list of str
            ``key.path=value`` strings (values parsed as TOML), as ``imdrive run --set``.

        Returns
        -------
        Scenario
            The validated scenario.
        """
        from imdrive.config.presets import preset_names, scenario_text

        if str(preset_or_path).endswith(".json") and preset_or_path not in preset_names():
            return cls._from_summary(preset_or_path, overrides)
        base_dir = None if preset_or_path in preset_names() else Path(preset_or_path).parent
        return cls.from_toml(scenario_text(preset_or_path), overrides, base_dir=base_dir)

    @classmethod
    def _from_summary(cls, path, overrides) -> Scenario:
        """The scenario a ``summary.json`` records (with overrides applied)."""
        import json

        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except OSError as exc:
            raise ConfigError("scenario", f"cannot read {path}: {exc}") from None
        except ValueError as exc:
            raise ConfigError("scenario", f"{path} is not valid JSON: {exc}") from None
        if not isinstance(data, dict) or not isinstance(data.get("scenario"), dict):
            raise ConfigError("scenario", f'{path} holds no "scenario" table (a summary.json)')
        data = data["scenario"]
        for ov in overrides:
            apply_override(data, ov)
        return cls.from_dict(data)

    def with_(self, **changes) -> Scenario:
        """A copy with whole sections replaced (``sc.with_(simulation=...)``), validated again.

        Parameters
        ----------
        **changes
            Field name -> new section object (or value for ``name``, ``description``).

        Returns
        -------
        Scenario
            The new, validated scenario.
        """
        return replace(self, **changes)

    def with_overrides(self, overrides) -> Scenario:
        """A new, validated scenario with dotted-key overrides applied.

        Parameters
        ----------
        overrides : list of str or dict
            ``["control.speed_ref_rpm=1500", "estimator.R2_ohm=0.9"]`` (values parsed as TOML,
            as ``--set`` does) or ``{"control.speed_ref_rpm": 1500, ...}``.

        Returns
        -------
        Scenario
            The new scenario; ``self`` is unchanged.

        Raises
        ------
        ConfigError
            Naming the key for an unknown setting or a value that breaks a rule.
        """
        if isinstance(overrides, str):
            _check_override_list(overrides)
        data = self.to_dict()
        if isinstance(overrides, dict):
            items = []
            for key, value in overrides.items():
                parts = tuple(str(key).split("."))
                if not is_setting(parts):
                    raise ConfigError(str(key), "no such setting")
                items.append((parts, value))
        else:
            items = [parse_override(o) for o in overrides]
        if getattr(self.simulation, "_log_every_auto", False):
            # the default decimation follows Ts_s: let it be derived again from the new one
            data["simulation"].pop("log_every", None)
        for parts, value in items:
            if parts[0] == "machine" and parts[-1] != "preset":
                data.setdefault("machine", {})
            set_path(data, parts, value)
        return Scenario.from_dict(data)

    # -- export ----------------------------------------------------------------------------
    def to_toml(self) -> str:
        """The scenario as TOML text, every default filled in (``imdrive show PRESET --all``).

        Returns
        -------
        str
            TOML text that :meth:`from_toml` reads back to an equal scenario.
        """
        from imdrive.config.toml_writer import dumps

        return dumps(self.to_dict())

    def to_dict(self) -> dict:
        """The scenario as run, every default filled in, in TOML-shaped form.

        Returns
        -------
        dict
            Section name -> table, in the units of the scenario file.
        """
        out: dict = {"name": self.name, "description": self.description}
        m = {"preset": self.machine_preset}
        m.update({k: v for k, v in self.machine.to_dict().items() if k != "description"})
        out["machine"] = m
        for key in SECTIONS:
            out[key] = _to_plain(getattr(self, key))
        return out


def _check_override_list(overrides) -> None:
    """A single string in place of the list of overrides is refused (it would be read one
    character at a time)."""
    if isinstance(overrides, str):
        raise ConfigError(
            "overrides",
            f"must be a list of 'key=value' strings, not a string (write [{overrides!r}])",
        )


def _to_plain(obj):
    if isinstance(obj, Profile):
        return obj.to_toml_value()
    if is_dataclass(obj):
        return {f.name: _to_plain(getattr(obj, f.name)) for f in fields(obj)}
    return obj


def _convert(tp, val, path: str):
    """Kept for :mod:`imdrive.sweep` (which passes the value to ``dataclasses.replace``).

    The settings classes validate their fields themselves now: the value is returned as is and
    the constructor that receives it checks and converts it, naming the same ``path``.
    """
    return val


# ------------------------------------------------------------------------------------------
# The file's keys, read off the settings classes (one walk for --set, sweeps, docs, schema),
# and the one override mechanism. They live here, beside the classes they walk, so that
# ``Scenario`` can apply overrides without an import cycle; :mod:`imdrive.config.schema` and
# :mod:`imdrive.config.overrides` re-export them.

#: Where a field of the Scenario object lives in the file.
FILE_PATHS = {"machine_preset": ("machine", "preset")}


@dataclass(frozen=True)
class Key:
    """One key of a scenario file.

    ``path`` is its dotted path (``("plant", "thermal", "tau1_s")``); ``owner`` the settings
    class that holds the field and ``name`` the field's name there; ``info`` its pydantic
    field (description, unit, constraints); ``hint`` its type without metadata (``float``,
    ``Literal[...]``, ``Profile | None``, a settings class); ``default`` its default
    (``dataclasses.MISSING`` for a machine field, which comes from the preset); ``table`` the
    settings class when the key is a table (a section or ``plant.thermal``).
    """

    path: tuple[str, ...]
    owner: type
    name: str
    info: FieldInfo
    hint: Any
    default: Any
    table: type | None

    @property
    def dotted(self) -> str:
        return ".".join(self.path)


def is_table_class(tp) -> bool:
    """Whether ``tp`` is a settings class (a pydantic dataclass), i.e. a table in the file."""
    return isinstance(tp, type) and hasattr(tp, "__pydantic_fields__")


def _fields(cls, prefix: tuple[str, ...]):
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        path = FILE_PATHS.get(f.name, (*prefix, f.name)) if cls is Scenario else (*prefix, f.name)
        hint = hints[f.name]
        table = hint if is_table_class(hint) else None
        yield Key(path, cls, f.name, cls.__pydantic_fields__[f.name], hint, f.default, table)


@functools.cache
def scenario_keys() -> tuple[Key, ...]:
    """Every key of a scenario file, tables included, in file order (sections as in
    :data:`~imdrive.config.scenario.SECTIONS`, ``[machine]`` first with ``preset``)."""
    top = {k.name: k for k in _fields(Scenario, ())}
    out = [top["name"], top["description"]]
    machine = top["machine"]
    out.append(machine)
    out.append(top["machine_preset"])
    for k in _fields(machine.table, ("machine",)):
        out.append(dataclasses.replace(k, default=dataclasses.MISSING))

    def walk(key: Key):
        out.append(key)
        for sub in _fields(key.table, key.path):
            if sub.table is not None:
                walk(sub)
            else:
                out.append(sub)

    for name in SECTIONS:
        walk(top[name])
    return tuple(out)


@functools.cache
def setting_paths() -> frozenset[tuple[str, ...]]:
    """Paths a single value may be set at: every key except the top-level tables."""
    return frozenset(k.path for k in scenario_keys() if not (k.table and len(k.path) == 1))


@functools.cache
def table_paths() -> frozenset[tuple[str, ...]]:
    """Paths of the tables of the file (``("machine",)``, ``("plant", "thermal")``, ...)."""
    return frozenset(k.path for k in scenario_keys() if k.table is not None)


def _schema_allows(path: list[str]) -> bool:
    """Whether a dotted override path names a field of the scenario schema.

    A field is a value (``simulation.Ts_s``, ``machine.preset``) or a table inside a section
    (``plant.thermal``); a whole section (``simulation``) is not one. The paths are read off
    the settings classes (:func:`scenario_keys`).
    """
    return tuple(path) in setting_paths()


def is_setting(parts) -> bool:
    """Whether the dotted path ``parts`` names a field of the scenario schema."""
    return bool(parts) and all(parts) and _schema_allows(list(parts))


def parse_override(spec: str) -> tuple[tuple[str, ...], object]:
    """Split ``key.path=value`` into the path and the value (parsed as a TOML value).

    A value that is not valid TOML is taken as a string, so ``control.speed_feedback=mras``
    needs no quotes.
    """
    if "=" not in spec:
        raise ConfigError(spec, "override must look like key.path=value")
    key, raw = spec.split("=", 1)
    key = key.strip()
    if not key:
        raise ConfigError("--set", f"{spec!r}: the key before '=' is empty")
    parts = tuple(key.split("."))
    if not is_setting(parts):
        raise ConfigError(key, "no such setting (see 'imdrive show PRESET' for the keys)")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return parts, value


def set_path(data: dict, parts, value) -> None:
    """Set the value at the dotted path ``parts`` of a TOML-shaped scenario dictionary.

    The one override mechanism: ``--set`` and every sweep axis go through it, and the
    scenario is validated once afterwards (:meth:`Scenario.from_dict`).
    """
    key = ".".join(parts)
    node = data
    for p in parts[:-1]:
        nxt = node.setdefault(p, {})
        if not isinstance(nxt, dict):
            raise ConfigError(key, f"{p} is not a table")
        node = nxt
    node[parts[-1]] = value


def apply_override(data: dict, spec: str) -> None:
    """Apply ``key.path=value`` to a scenario dictionary (see :func:`parse_override`)."""
    parts, value = parse_override(spec)
    set_path(data, parts, value)
