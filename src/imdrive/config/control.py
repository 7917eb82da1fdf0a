"""Settings of the controller: which controller drives the inverter, the open-loop voltage and
field-oriented speed control (sections ``[drive]``, ``[open_loop]``, ``[control]``).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import AfterValidator, model_validator

from imdrive.config.estimators import ESTIMATOR_SETTINGS
from imdrive.config.profiles import Profile
from imdrive.config.validation import Bool, Float, Int, ProfileValues, Str, setting, settings
from imdrive.errors import ConfigError

C = Profile.constant
PositiveProfile = Annotated[Profile, ProfileValues(gt=0.0)]
NonNegativeProfile = Annotated[Profile, ProfileValues(ge=0.0)]


def _known_estimator(name: str) -> str:
    """``"measured"`` or a registered estimator (the package's, or a plug-in's)."""
    if name != "measured" and name not in ESTIMATOR_SETTINGS:
        from imdrive.config.plugins import looked_past

        if looked_past():  # shown, not run: the unimported plug-in may define it
            return name
        first = ("measured", "mras", "reactive-mras", "afo", "ekf")  # the package's, in order
        known = [n for n in first if n == "measured" or n in ESTIMATOR_SETTINGS]
        known += [n for n in ESTIMATOR_SETTINGS if n not in first]
        raise ConfigError("", "must be one of " + ", ".join(repr(n) for n in known))
    return name


@settings("drive")
class DriveSettings:
    """Which controller drives the inverter (``[drive]``)."""

    mode: Annotated[
        Literal["open-loop", "vector"],
        setting(
            '"open-loop" (the default): the machine on the sinusoidal voltage of [open_loop]; '
            "[control], [estimator], [compensator], [injection] and the estimators' sections "
            "are unused, so a file that sets any of them without a [drive] mode gets a "
            'deprecation warning (it will be refused in a later release); "vector": '
            "field-oriented speed control ([control]) with its speed feedback, estimator and "
            'compensator. Every vector preset sets "vector"'
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
        Str,
        AfterValidator(_known_estimator),
        setting(
            '"measured": encoder speed; sensorless, the estimate of: "mras" Schauder\'s MRAS, '
            '"reactive-mras" the reactive-power MRAS, "smo-mras" the sliding-mode MRAS, "afo" '
            'the adaptive full-order observer, "ekf" the extended Kalman filter '
            "(docs/estimators.md), or an estimator registered by a module of [plugins] modules"
        ),
    ] = "measured"
    speed_ref_rpm: Annotated[Profile, setting("speed reference", "rpm")] = C(0.0)
    speed_ref_pu: Annotated[
        Profile | None,
        setting(
            "speed reference in per-unit of the machine's rated speed (its nameplate's, "
            "config/rated.py), times in s: the same profile on every machine "
            "(config/sequence.py); the per-unit twin of speed_ref_rpm",
            default_doc="unset: speed_ref_rpm",
        ),
    ] = None
    premagnetise_T2: Annotated[
        Float,
        setting(
            "the drive builds the rotor flux at standstill for this many rotor time constants "
            "of its model, T̂2 = L̂2/R̂2(0), before it releases the speed reference (95 % of the "
            "flux at 3): a speed reference that moves earlier is delayed with the load and the "
            "run's end (config/sequence.py); with mras.R1_standstill it lasts until the "
            "standstill test has its window too; 0: released at once",
            ge=0.0,
            le=20.0,
        ),
    ] = 3.0
    ramp_torque_limit: Annotated[
        Bool,
        setting(
            "a speed ramp steeper than the drive's torque limit allows (the current limit at "
            "the reference flux, less the load, over J; above the rated speed at constant "
            "power and below the breakdown torque) is followed at 0.9 of that acceleration, as "
            "a drive's ramp generator does, and the run says so (config/sequence.py); steps are "
            "left as given"
        ),
    ] = True
    flux_ref_Wb: Annotated[
        PositiveProfile | None,
        setting(
            "rotor-flux reference (> 0)",
            "Wb",
            derived=True,
        ),
    ] = None
    speed_bandwidth_Hz: Annotated[
        Float | None,
        setting(
            "speed-loop bandwidth the speed PI gains are derived from",
            "Hz",
            gt=0.0,
            derived=True,
        ),
    ] = None
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
            derived=True,
        ),
    ] = None
    decoupling: Annotated[
        Bool, setting("cross-coupling and back-emf feed-forward in the current controllers")
    ] = True
    current_controller: Annotated[
        Literal["pi", "imc"] | None,
        setting(
            '"pi": synchronous-frame PIs by pole-zero cancellation, the cross-coupling '
            'decoupled on the references; "imc": internal model control (Harnefors and Nee '
            "1998): the cross-coupling decoupled on the measured current and an active "
            "resistance, so an error of the back-emf's feed-forward is rejected at the current "
            "loop's bandwidth (kernels/current_control.py)",
            derived=True,
        ),
    ] = None
    field_weakening: Annotated[
        Bool | None,
        setting(
            "field weakening above base speed: the flux reference is scaled down by a voltage "
            "feedback that holds the voltage use at field_weakening_voltage "
            "(kernels/ifoc.py, field_weakening); turns the injection's headroom on",
            derived=True,
        ),
    ] = None
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
    field_weakening_bound: Annotated[
        Bool,
        setting("field weakening: flux factor at most the no-load one at field_weakening_voltage"),
    ] = True
    speed_gain_flux_scaling: Annotated[
        Bool | None,
        setting(
            "in field weakening the speed PI's gains times the flux factor k (kp) and k^2 (ki): "
            "an estimator's speed error from a wrong R2_hat is proportional to the torque "
            "current and grows as 1/k, a positive feedback through the speed PI that made the "
            "loop limit-cycle at twice the rated speed (kernels/speed_control.py)",
            derived=True,
        ),
    ] = None
    reorientation: Annotated[
        Bool,
        setting(
            "above half the rated stator frequency, realign the controller's frame on the "
            "rotor flux (seen in the back-emf) when the voltage limit has left it more than 60 "
            "degrees off for 50 ms (kernels/ifoc.py, check_orientation); off by default: "
            "it rescues the ideal drive's frame locked 90 degrees off at twice the rated "
            "speed but on the dead-time bridge more runs lost control with it "
            "(docs/envelope.md)"
        ),
    ] = False
    dead_time_compensation: Annotated[
        Literal["none", "feedforward"],
        setting(
            '"feedforward": add sgn(i) t_d f_sw Vdc_meas to each phase voltage reference '
            "(measured current, smooth over inverter.sign_band_A)"
        ),
    ] = "none"
    dead_time_compensation_band: Annotated[
        Literal["ripple", "fixed"],
        setting(
            '"ripple": on the switching bridge each phase\'s compensation has the shape of the '
            "bridge's loss, none while the current's ripple at the leg's commutations "
            "(computed from the voltage reference) straddles zero and whole beyond it "
            "(kernels/ifoc.py, commutation_ripple; the fixed band, wider than that ripple at "
            "low speed, stalled the current at its zero crossings and biased R2_hat 2-7 % low "
            "at 0.1 of the rated speed), taken at the current turned to the middle of the "
            "period where it acts, and the modulator moves every gate command earlier by half "
            "the assumed dead time (the dead time delays the pulses' centres by that, and the "
            "current sample then biased the MRAS's estimate in proportion to the speed; "
            'kernels/ifoc.py, dead_time_advance); "fixed": the sign smooth over '
            "inverter.sign_band_A throughout, at the sample's current, no advance. The average "
            "model's loss changes sign over inverter.sign_band_A, so there the band is that in "
            "either case"
        ),
    ] = "ripple"
    dead_time_compensation_s: Annotated[
        Float | None,
        setting(
            "the dead time the compensation assumes",
            "s",
            ge=0.0,
            derived=True,
        ),
    ] = None
    inverter_error_adaptation_per_s: Annotated[
        Float | None,
        setting(
            "rate of the online scaling of the inverter-error compensation (dead-time "
            "feed-forward or the identified table) that nulls the sixth harmonic its residual "
            "leaves in the current controllers' output; 0: off (the compensation as assumed)",
            "1/s",
            ge=0.0,
            le=100.0,
            derived=True,
        ),
    ] = None
    inverter_error_signal: Annotated[
        Literal["stator-voltage", "current-loop"],
        setting(
            "where the online scaling reads the residual's sixth harmonic: "
            '"stator-voltage", the stator voltage equation over each period (the applied '
            "voltage less the compensation, sigma_L1 di/dt and R1_hat i; kernels/"
            'inverter_scale.py stator_residual); "current-loop", the current controllers\' '
            "output (on a sensorless drive at light load the speed estimate's sixth harmonic "
            "reaches it through the speed loop and turned the law's sign at 1.5 x the rated "
            "speed)"
        ),
    ] = "stator-voltage"
    inverter_error_adaptation_fmin_pu: Annotated[
        Float,
        setting(
            "the scaling adapts only above this stator frequency, per-unit of the machine's "
            "rated frequency (its sixth harmonic then lies well above the R2 injection)",
            ge=0.0,
            le=1.0,
        ),
    ] = 0.05
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
