"""Settings of the adaptive full-order flux observer (section ``[afo]``), registered with the
others of :mod:`imdrive.config.estimators` (which imports this module)."""

from __future__ import annotations

import math
from typing import Annotated, Literal

from imdrive.config.defaults import Derived, register_derived, uses_estimator
from imdrive.config.registry import EstimatorContext, EstimatorRecords, estimator_settings
from imdrive.config.scaled import afo_resistance_bandwidths, flux_injection_frequency_Hz
from imdrive.config.validation import Bool, Float, setting
from imdrive.design.estimators import afo_regeneration_gain, default_afo_gains


@estimator_settings(
    "afo", "afo", description="adaptive full-order flux observer", legend="full-order observer"
)
class AfoSettings:
    """Adaptive full-order flux observer (``[afo]``, Kubota, Matsuse & Nakano 1993).

    Gains default from the bandwidths (:mod:`imdrive.design.estimators`).
    """

    gain: Annotated[
        Literal["regeneration", "scheduled", "fixed"],
        setting(
            "observer gain: \"scheduled\" g2 = -rho' (R̂1 + σL1 g1) L2/M with rho' the share "
            "the operating point needs for stable regeneration, 0 motoring, up to rho near "
            "zero stator frequency (kernels/estimators/afo.py, scheduled_rho; the default "
            "since 2026-11-29: on the realistic drive at 45-100 rpm the constant gain lost "
            'control regenerating the rated torque at 70 rpm); "regeneration" the same with '
            'rho throughout; "fixed" g1, g2 as given (g1 = g2 = 0: the plain observer)'
        ),
    ] = "scheduled"
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
        Float | None,
        setting(
            "speed-adaptation bandwidth Kp, Ki are derived from (config/estimators_afo.py, "
            "afo_bandwidth_Hz)",
            "Hz",
            gt=0.0,
            derived=True,
        ),
    ] = None
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
        Float | None,
        setting(
            "R̂1 adaptation rate the gain is derived from; the absolute twin of R1_bandwidth_pu",
            "rad/s",
            gt=0.0,
            derived=True,
        ),
    ] = None
    R1_bandwidth_pu: Annotated[
        Float | None,
        setting(
            "R1_bandwidth_rad_s in per-unit of the machine's rotor corner 1/T2 = R2/L2 (as "
            "mras.R1_rate_pu)",
            gt=0.0,
            default_doc="unset: R1_bandwidth_rad_s",
        ),
    ] = None
    R2_bandwidth_rad_s: Annotated[
        Float | None,
        setting(
            'R̂2 adaptation rate (estimator.R2_adaptation = "afo"; needs [flux_injection]); '
            "the absolute twin of R2_bandwidth_pu",
            "rad/s",
            gt=0.0,
            derived=True,
        ),
    ] = None
    R2_bandwidth_pu: Annotated[
        Float | None,
        setting(
            "R2_bandwidth_rad_s in per-unit of the machine's rotor corner 1/T2 = R2/L2, so it "
            "stays as far below the flux injection (flux_injection.frequency_pu) on every "
            "machine",
            gt=0.0,
            default_doc="unset: R2_bandwidth_rad_s",
        ),
    ] = None

    def records(self, ctx: EstimatorContext) -> EstimatorRecords:
        """Adaptation gains (:func:`default_afo_gains`) and the observer gain.

        Parameters
        ----------
        ctx : EstimatorContext
            The controller's model and the drive.

        Returns
        -------
        EstimatorRecords
        """
        sc = ctx.scenario
        bandwidth_Hz = afo_bandwidth_Hz(sc, self)
        own_R2 = sc.estimator.R2_adaptation == "afo"
        Kp, Ki, k_R1, k_R2 = default_afo_gains(
            ctx.psi0,
            ctx.R1_hat,
            ctx.R2_hat,
            ctx.sigma_L1_hat,
            ctx.M_hat,
            ctx.L2_hat,
            self.g1_per_s,
            2 * math.pi * bandwidth_Hz,
            *afo_resistance_bandwidths(self, sc.machine),
            sc.flux_injection.amplitude,
            2 * math.pi * flux_injection_frequency_Hz(sc),
        )
        regen = self.gain in ("regeneration", "scheduled")
        g2 = self.g2_ohm
        if regen:
            g2 = afo_regeneration_gain(
                ctx.R1_hat, ctx.sigma_L1_hat, ctx.M_hat, ctx.L2_hat, self.g1_per_s, self.rho
            )
        Kp = self.Kp if self.Kp is not None else Kp
        Ki = self.Ki if self.Ki is not None else Ki
        params = dict(
            gain_mode=_afo_gain_mode(self.gain, sc.estimator.R2_adaptation == "afo"),
            rho=self.rho,
            g1=self.g1_per_s,
            g2=self.g2_ohm,
            Kp=Kp,
            Ki=Ki,
            # the schedule slows the adaptation to half (kernels/estimators/afo.py
            # adaptation_share): not the observer's own R2 law's, already at that half
            a_w=2 * math.pi * bandwidth_Hz if self.Kp is None and not own_R2 else 0.0,
            k_R1=k_R1 if self.R1_adaptation else 0.0,
            k_R2=k_R2 if own_R2 else 0.0,
            R_min=0.5,
            R_max=2.0,
        )
        derived = {
            "afo_bandwidth_Hz": bandwidth_Hz,
            "afo_Kp": Kp,
            "afo_Ki": Ki,
            "afo_g1_per_s": self.g1_per_s,
            "afo_g2_ohm": g2,
        }
        return EstimatorRecords(params, derived=derived)


#: The observer's speed-adaptation bandwidth over the speed loop's (:func:`afo_bandwidth_Hz`)
AFO_PER_SPEED_BANDWIDTH = 16.0
#: ... where the observer adapts R2 itself (``estimator.R2_adaptation = "afo"``)
AFO_PER_SPEED_BANDWIDTH_OWN_R2 = 8.0


def afo_bandwidth_Hz(sc, afo=None) -> float:
    """The observer's speed-adaptation bandwidth, Hz: ``afo.bandwidth_Hz`` if set, else
    :data:`AFO_PER_SPEED_BANDWIDTH` (16) times the speed loop's bandwidth
    (:func:`imdrive.config.perunit.speed_bandwidth_Hz`): 80 Hz on Table IV.

    The speed loop acts on the estimate, and where R̂2 is off the estimate carries a slip
    error that follows the torque the loop commands: a loop through the estimator's
    adaptation that the speed loop must not see. With 8 times the speed loop's bandwidth
    (the fixed 40 Hz of rounds 2-4 on a 5 Hz loop) the observer drive from R̂2(0) = 1.3 R2
    oscillated at 0.3-0.5 of the rated speed with a growing amplitude (Table IV at 0.3 with no
    load: the estimate 157 rpm off at the end; Krause 3 hp and 50 hp at half speed lost
    control), whatever the load; on Table IV at 0.3 of the rated speed the speed adaptation at
    4 and 8 times the speed loop's bandwidth ends 123 and 157 rpm off, at 12 and 16 times
    exact, and a 2 Hz speed loop with 40 Hz (20 times) exact too. On the machine envelope of
    the two observer drives (`injection-robust-afo`, `sensorless-afo`, 672 runs) 40 Hz
    converged in 653 runs and lost 8; 60, 80 and 160 Hz converged in 663, 668 and 665 and lost
    none; 10 Hz in 589 (with the frame on the observer's flux at every frequency); this rule
    with the kernel's slower adaptation at low stator frequency (below) 666, none lost. The
    zero-frequency study (168 runs of the two): 40 Hz 132 converged and 1 lost, 80 Hz 132
    and none, this rule 131 and 1.

    Below a sixth of that bandwidth in stator frequency the kernel slows the adaptation, to
    half at most (:func:`imdrive.kernels.estimators.afo.adaptation_share`: a dead-time
    bridge's sixth harmonic there biased the estimate), so at low speed it runs at 8 times
    the speed loop as before.

    Where the observer adapts R2 itself (``estimator.R2_adaptation = "afo"``) its R2 law and
    its speed law read the same current error, and the speed law stays at
    :data:`AFO_PER_SPEED_BANDWIDTH_OWN_R2` (8) times the speed loop: at 16 times that drive
    lost control in 7 of the realistic drive's 10 bench cases (docs/estimators.md,
    ``afo+R2``) against 4 at 8 times.

    Parameters
    ----------
    sc : Scenario
    afo : AfoSettings, optional
        The observer's settings (default ``sc.afo``).

    Returns
    -------
    float
        Bandwidth, Hz.
    """
    from imdrive.config.perunit import speed_bandwidth_Hz

    afo = sc.afo if afo is None else afo
    if afo.bandwidth_Hz is not None:
        return afo.bandwidth_Hz
    own_R2 = sc.estimator.R2_adaptation == "afo"
    ratio = AFO_PER_SPEED_BANDWIDTH_OWN_R2 if own_R2 else AFO_PER_SPEED_BANDWIDTH
    return ratio * speed_bandwidth_Hz(sc)


def _afo_gain_mode(gain: str, adapts_R2: bool) -> int:
    """The kernel's ``gain_mode`` (kernels/estimators/afo.py): 0 fixed, 1 the constant
    regeneration gain, 2 scheduled. The observer's own R2 law (``estimator.R2_adaptation =
    "afo"``) keeps the constant gain under ``"scheduled"``: it reads R2 from the current error,
    which needs the flux estimate the voltage model gives (``rho`` near 1) rather than the
    current model's, itself built on R2_hat. Measured on the average drive (docs/estimators.md,
    ``afo+R2``): from R2_hat = 0.8 R2 it ended +1.6 % with the constant gain and +42 % with
    the scheduled one, and lost control at the load steps."""
    if gain == "regeneration" or (gain == "scheduled" and adapts_R2):
        return 1
    return 2 if gain == "scheduled" else 0


def _bandwidth(sc) -> float:
    return afo_bandwidth_Hz(sc, sc.afo)


def _R1_bandwidth(sc) -> float:
    return afo_resistance_bandwidths(sc.afo, sc.machine)[0]


def _R2_bandwidth(sc) -> float:
    return afo_resistance_bandwidths(sc.afo, sc.machine)[1]


_RESISTANCE_RATE = (
    "Table IV's 2 rad/s scaled by the rotor corner 1/T2 (0.175 × it; config/scaled.py "
    "afo_resistance_bandwidths)"
)
register_derived(
    Derived(
        "afo.bandwidth_Hz",
        "16 x the speed loop's bandwidth (80 Hz on Table IV); 8 x with the observer's own R2 "
        'law (estimator.R2_adaptation = "afo")',
        _bandwidth,
        uses_estimator("afo"),
    ),
    Derived("afo.R1_bandwidth_rad_s", _RESISTANCE_RATE, _R1_bandwidth, uses_estimator("afo")),
    Derived("afo.R2_bandwidth_rad_s", _RESISTANCE_RATE, _R2_bandwidth, uses_estimator("afo")),
)
