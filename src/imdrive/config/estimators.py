"""Settings of the controller's machine model and of the speed estimators (sections
``[estimator]``, ``[mras]``, ``[reactive_mras]``, ``[afo]``, ``[ekf]``, ``[flux_injection]``).

A speed estimator's settings class is its Python half: besides its validated settings it says
how they and the controller's machine model become the estimator's parameter and initial-state
records (its gain design, :meth:`records`), and the unit of each log field the estimator adds.
:func:`estimator_settings` registers such a class under the name ``control.speed_feedback``
selects; the compiled half (records, step function) is registered under the same name in
:mod:`imdrive.kernels.estimators.registry`, and :mod:`imdrive.run.estimators` joins the two.
The package's four estimators are declared this way; an estimator outside the package too
(its settings then live in the scenario's ``[plugins.settings.NAME]`` table).
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from imdrive.config.mras_regeneration import (
    RegenerationAngle,
    RegenerationBand,
    RegenerationGain,
    RegenerationSpeed,
    regeneration_params,
)
from imdrive.config.r1_standstill import StandstillHold
from imdrive.config.registry import (  # noqa: F401  (re-exported: the settings half's API)
    ESTIMATOR_SETTINGS,
    EstimatorContext,
    EstimatorRecords,
    PeriodMeanCurrent,
    estimator_names,
    estimator_settings,
    package_sections,
)
from imdrive.config.validation import Bool, Float, Int, setting, settings
from imdrive.design.estimators import (
    default_reactive_mras_gains,
)
from imdrive.design.gains import default_mras_gains, mras_type2_gains
from imdrive.errors import ConfigError


@settings("estimator")
class EstimatorSettings:
    """The controller's and estimator's machine model (``[estimator]``); unset: the plant's."""

    R1_ohm: Annotated[
        Float | None,
        setting("stator resistance", "ohm", gt=0.0, derived=True),
    ] = None
    R2_ohm: Annotated[
        Float | None,
        setting("rotor resistance: the initial estimate R̂2", "ohm", gt=0.0, derived=True),
    ] = None
    Ll1_H: Annotated[
        Float | None, setting("stator leakage inductance", "H", gt=0.0, derived=True)
    ] = None
    Ll2_H: Annotated[
        Float | None, setting("rotor leakage inductance", "H", gt=0.0, derived=True)
    ] = None
    M_H: Annotated[
        Float | None,
        setting("magnetising inductance", "H", gt=0.0, derived=True),
    ] = None
    R1_ratio: Annotated[
        Float | None,
        setting(
            "R̂1 as a multiple of the plant's R1 (a starting error that follows the machine; "
            "instead of R1_ohm)",
            gt=0.0,
            default_doc="unset: R1_ohm",
        ),
    ] = None
    R2_ratio: Annotated[
        Float | None,
        setting(
            "the initial R̂2 as a multiple of the plant's R2 (instead of R2_ohm)",
            gt=0.0,
            default_doc="unset: R2_ohm",
        ),
    ] = None
    M_ratio: Annotated[
        Float | None,
        setting(
            "M̂ as a multiple of the plant's M (instead of M_H)", gt=0.0, default_doc="unset: M_H"
        ),
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


@estimator_settings(
    "reactive-mras", "reactive_mras", description="reactive-power MRAS speed estimator"
)
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

    def records(self, ctx: EstimatorContext) -> EstimatorRecords:
        """K1, K2 from the bandwidth (:func:`default_reactive_mras_gains`), each overridable.

        Parameters
        ----------
        ctx : EstimatorContext
            The controller's model and the drive.

        Returns
        -------
        EstimatorRecords
        """
        K1, K2 = default_reactive_mras_gains(ctx.psi0, ctx.L2_hat, 2 * math.pi * self.bandwidth_Hz)
        K1 = self.K1 if self.K1 is not None else K1
        K2 = self.K2 if self.K2 is not None else K2
        derived = {"reactive_mras_K1": K1, "reactive_mras_K2": K2}
        return EstimatorRecords(dict(K1=K1, K2=K2), derived=derived)


# the adaptive observer's settings live in their own module (this one's size); imported here
# so it registers in its place among the others, and the old import path works
from imdrive.config.estimators_afo import AfoSettings  # noqa: E402,F401

# the EKF's settings live in their own module (this one's size); imported here so it registers
# in its place among the others, and the old import path works
from imdrive.config.estimators_ekf import EkfSettings  # noqa: E402,F401


@settings("flux_injection")
class FluxInjectionSettings:
    """A sinusoid on the rotor-flux command (``[flux_injection]``), the excitation under which
    R2 and the speed are estimated together (Kubota & Matsuse 1994); 0 = off."""

    amplitude: Annotated[
        Float, setting("relative amplitude of the sinusoid on the flux command", ge=0.0, lt=1.0)
    ] = 0.0
    frequency_Hz: Annotated[
        Float | None,
        setting(
            "frequency of the sinusoid; the absolute twin of frequency_pu",
            "Hz",
            gt=0.0,
            derived=True,
        ),
    ] = None
    frequency_pu: Annotated[
        Float | None,
        setting(
            "frequency_Hz in per-unit of the controller's rotor corner R̂2(0)/(2π L̂2), as "
            "injection.frequency_pu: the flux follows its command through the rotor's corner",
            gt=0.0,
            default_doc="Table IV's 2 Hz scaled by the machine's rotor corner (1.098 × it)",
        ),
    ] = None


_WB = ("Wb", 1.0)


@estimator_settings(
    "mras",
    "mras",
    log_units={f: _WB for f in ("lam_v_alpha", "lam_v_beta", "lam_i_alpha", "lam_i_beta")}
    | {"R1_id_status": ("code", 1.0)},
    flux_error=True,
    description="Schauder's MRAS speed estimator",
    legend="MRAS",
)
class MrasSettings:
    """Schauder's MRAS speed estimator (``[mras]``).

    ``K1``, ``K2`` default from ``bandwidth_Hz`` (:func:`imdrive.design.gains.default_mras_gains`);
    with ``acceleration_tracking`` (by default on machines whose rated acceleration the
    type-1 loop would lag by more than half the rotor's corner frequency) a second
    integrator after the PI, corner ``bandwidth/4``
    (:func:`imdrive.design.gains.mras_type2_gains`).
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
    wc_per_stator_frequency: Annotated[
        Float,
        setting(
            "below wc_rad_s the filter's cut-off follows the stator frequency, "
            "max(wc_min_rad_s, this x |ω_e|), so the adaptation keeps 1/(1 + this²) of its "
            "gain where a fixed cut-off would leave ω_e²/(ω_e² + ωc²) (0.07 at 20 rpm, no "
            "load, on Table IV) and the speed loop outruns its estimate (0: a fixed cut-off; "
            "kernels/estimators/mras.py)",
            ge=0.0,
        ),
    ] = 0.0
    wc_min_rad_s: Annotated[
        Float,
        setting(
            "the floor of the cut-off that follows the stator frequency "
            "(wc_per_stator_frequency): near zero stator frequency a smaller one lets offsets "
            "and start-up transients of the voltage model decay more slowly (with an R̂1 "
            "error dR1 its DC flux error is (L2/M) dR1 |i| / ωc)",
            "rad/s",
            gt=0.0,
        ),
    ] = 5.0
    wc_follow_time_s: Annotated[
        Float,
        setting(
            "time constant of the flux frequency the cut-off follows "
            "(wc_per_stator_frequency): longer than the R2 compensator's injection period, "
            "so the cut-off does not follow the injection's flux modulation (a cut-off "
            "modulated in phase with the injection doubled the R̂2 bias an R̂1 error leaves: "
            "+2.4 % at 0.1 x rated speed regenerating on Table IV with R̂1 1 % low, against "
            "+1.1 % with 0.5 s)",
            "s",
            gt=0.0,
        ),
    ] = 0.5
    bandwidth_Hz: Annotated[
        Float | None,
        setting(
            "bandwidth K1 and K2 are derived from (docs/stability.md)",
            "Hz",
            gt=0.0,
            derived=True,
        ),
    ] = None
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
    R1_rate_pu: Annotated[
        Float | None,
        setting(
            "online R1 estimation: rate per-unit of the machine's rotor corner 1/T2 = R2/L2, "
            "so it stays as far below the injection (injection.frequency_pu) on every machine",
            gt=0.0,
            default_doc="unset: R1_rate_per_s",
        ),
    ] = None
    normalise: Annotated[
        Bool | None,
        setting(
            "scale the adaptation error by (design flux / estimated flux)², so the loop keeps "
            "its bandwidth in field weakening (kernels/estimators/mras.py)",
            derived=True,
        ),
    ] = None
    R1_standstill: Annotated[
        Bool,
        setting(
            "standstill R1 identification by the drive, whatever control.speed_feedback (the "
            "key keeps its [mras] name): while the speed reference is zero and the flux "
            "current flows, R̂1 = Σ v·i / Σ |i|² over the part after the measured flux build-up, "
            "applied when the reference leaves zero, log column R1_id_status 1 identified, 2 "
            "could not, 3 one level of two (then the run's verdict_text says so; "
            "kernels/r1_standstill.py); at one level biased by the dead-time "
            "compensation's residual (1.13 R1 on the envelope's bridge), at two levels not "
            "(R1_standstill_levels)"
        ),
    ] = False
    R1_standstill_levels: Annotated[
        Int | None,
        setting(
            "R1_standstill at 1 current level (R̂1 holds the dead-time compensation's residual "
            "voltage / |i|) or 2 (R̂1 = Δu/Δi, Holtz & Quan 2002; the residual starts the "
            "compensation's scale): the flux current at R1_standstill_first_level of its "
            "reference, then at it; the duty cycle waits for the test at most "
            "R1_standstill_hold_T2 (kernels/r1_standstill.py)",
            ge=1,
            le=2,
            derived=True,
        ),
    ] = None
    R1_standstill_first_level: Annotated[
        Float,
        setting("the two-level test's first flux level, per unit of the reference", gt=0.2, le=0.8),
    ] = 0.6
    R1_standstill_hold_T2: StandstillHold = 16.0
    R1_max_freq_Hz: Annotated[
        Float | None,
        setting(
            "online R1 estimation runs below this stator frequency (and in motoring only); "
            "the absolute twin of R1_max_freq_pu",
            "Hz",
            gt=0.0,
            derived=True,
        ),
    ] = None
    R1_max_freq_pu: Annotated[
        Float,
        setting(
            "online R1 estimation runs below this stator frequency, per-unit of the machine's "
            "rated frequency (0.5: 30 Hz on Table IV, the bound the law was measured with; "
            "unless R1_max_freq_Hz is set)",
            gt=0.0,
        ),
    ] = 0.5
    period_mean_current: PeriodMeanCurrent = True
    regeneration_angle_deg: RegenerationAngle = 80.0
    regeneration_band_pu: RegenerationBand = 0.005
    regeneration_speed_pu: RegenerationSpeed = 0.005
    regeneration_gain: RegenerationGain = 0.0
    acceleration_tracking: Annotated[
        Bool | None,
        setting(
            "type-2 adaptation: a second integral of the error, so the estimate follows a "
            "constant acceleration without lag (its corner from bandwidth_Hz; "
            "design/gains.py mras_type2_gains)",
            derived=True,
        ),
    ] = None
    acceleration_tracking_from_pu: Annotated[
        Float,
        setting(
            "the type-2 adaptation's second integral runs above this stator frequency, "
            "per-unit of the machine's rated frequency (below it, where the voltage model has "
            "little signal, it is held)",
            ge=0.0,
            lt=1.0,
        ),
    ] = 0.05

    def records(self, ctx: EstimatorContext) -> EstimatorRecords:
        """K1, K2 from the bandwidth (:func:`default_mras_gains`), each overridable; the R1
        laws' clamps and the flux normalisation.

        Parameters
        ----------
        ctx : EstimatorContext
            The controller's model and the drive.

        Returns
        -------
        EstimatorRecords
        """
        from imdrive.config.mras_bandwidth import mras_bandwidth_Hz

        sc = ctx.scenario
        T2_hat = ctx.L2_hat / ctx.R2_hat
        a = 2 * math.pi * mras_bandwidth_Hz(sc, self)
        b2 = 0.0
        f_rated = sc.machine.rated_frequency_Hz
        if mras_type2(sc, self, T2_hat):
            K1, K2, b2 = mras_type2_gains(ctx.psi0, T2_hat, a)
        else:
            K1, K2 = default_mras_gains(ctx.psi0, T2_hat, a)
        K1 = self.K1 if self.K1 is not None else K1
        K2 = self.K2 if self.K2 is not None else K2
        normalise = mras_normalise(sc, self)
        if self.R1_rate_pu is not None and self.R1_rate_per_s != 0.0:
            raise ConfigError(
                "mras.R1_rate_pu", "set mras.R1_rate_per_s or mras.R1_rate_pu, not both"
            )
        k_R1 = self.R1_rate_per_s if self.R1_rate_pu is None else self.R1_rate_pu / sc.machine.T2_s
        params = {
            "wc": self.wc_rad_s,
            "wc_k": self.wc_per_stator_frequency,
            "wc_min": self.wc_min_rad_s,
            "wc_tau": self.wc_follow_time_s,
            "K1": K1,
            "K2": K2,
            "b2": b2,
            "b2_wmin": self.acceleration_tracking_from_pu * 2 * math.pi * f_rated,
            "k_R1": k_R1,
            "R1_fmax": r1_max_freq_Hz(self, f_rated),
            "R1_min": 0.5 * ctx.R1_hat,
            "R1_max": 2.0 * ctx.R1_hat,
            "psi2_norm": ctx.psi0 * ctx.psi0 if normalise else 0.0,
            "bend": self.period_mean_current,
            **regeneration_params(self, sc.machine, ctx.psi0),
        }
        src = {
            "mras_K1": "mras.K1" if self.K1 is not None else "mras.bandwidth_Hz",
            "mras_K2": "mras.K2" if self.K2 is not None else "mras.bandwidth_Hz",
        }
        derived = {"mras_K1": K1, "mras_K2": K2}
        if self.R1_rate_pu is not None:
            derived["mras_R1_rate_per_s"], src["mras_R1_rate_per_s"] = k_R1, "mras.R1_rate_pu"
        if b2 > 0.0:
            derived["mras_b2"] = b2
            src["mras_b2"] = "mras.bandwidth_Hz"
        return EstimatorRecords(params, derived=derived, sources=src)


# the type-2 rule lives with its criteria (this module's size); the old import path works
# the sliding-mode MRAS's settings live in their own module (this one's size); imported here
# so it registers after the others, as before, and the old import path works
from imdrive.config.estimators_smo import SmoMrasSettings  # noqa: E402,F401
from imdrive.config.mras_bandwidth import (  # noqa: E402,F401
    mras_normalise,
    mras_type2,
    r1_max_freq_Hz,
)
