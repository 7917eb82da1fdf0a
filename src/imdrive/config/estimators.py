"""Settings of the controller's machine model and of the speed estimators (sections
``[estimator]``, ``[mras]``, ``[reactive_mras]``, ``[afo]``, ``[ekf]``, ``[flux_injection]``).
"""

from __future__ import annotations

from typing import Annotated, Literal

from imdrive.config.validation import Bool, Float, setting, settings


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
