"""Settings of the extended Kalman filter for speed and R2 (section ``[ekf]``), registered with
the others of :mod:`imdrive.config.estimators` (which imports this module)."""

from __future__ import annotations

from typing import Annotated

from imdrive.config.defaults import Derived, register_derived, uses_estimator
from imdrive.config.registry import EstimatorContext, EstimatorRecords, estimator_settings
from imdrive.config.validation import Float, setting
from imdrive.design.estimators import default_ekf_noise


@estimator_settings(
    "ekf", "ekf", description="extended Kalman filter for speed and R2", legend="EKF"
)
class EkfSettings:
    """Extended Kalman filter for speed and R2 (``[ekf]``); noise as standard deviations.

    Per-period variances: currents ``(voltage_noise_V Ts / σL1)²``, fluxes
    ``(flux_noise_Wb_per_s Ts)²``... see :func:`imdrive.design.estimators.default_ekf_noise`.
    Each noise is given in SI or in per-unit of the machine quantity it scales with (rated
    voltage, flux rate ``psi_rated / T2``, rated acceleration, R2 / T2, rated current); unset, Table
    IV's tuning scaled by that quantity (:func:`imdrive.config.scaled.ekf_noise`).
    """

    voltage_noise_V: Annotated[
        Float | None,
        setting(
            "voltage uncertainty behind the current's process noise; the absolute twin of "
            "voltage_noise_pu",
            "V",
            gt=0.0,
            derived=True,
        ),
    ] = None
    voltage_noise_pu: Annotated[
        Float | None,
        setting(
            "voltage_noise_V in per-unit of the machine's rated phase voltage peak "
            "sqrt(2/3) V_ll (the inverter's voltage error scales with the DC link)",
            gt=0.0,
            default_doc="unset: voltage_noise_V",
        ),
    ] = None
    flux_noise_Wb_per_s: Annotated[
        Float | None,
        setting(
            "rotor-flux process noise density; the absolute twin of flux_noise_pu",
            "Wb/s",
            gt=0.0,
            derived=True,
        ),
    ] = None
    flux_noise_pu: Annotated[
        Float | None,
        setting(
            "flux_noise_Wb_per_s in per-unit of psi_rated / T2, the rate of the rotor-flux "
            "model's R2-dependent term (M i - psi) / T2",
            gt=0.0,
            default_doc="unset: flux_noise_Wb_per_s",
        ),
    ] = None
    acceleration_noise_rad_s2: Annotated[
        Float | None,
        setting(
            "speed process noise: electrical acceleration uncertainty; the absolute twin of "
            "acceleration_noise_pu",
            "rad/s²",
            gt=0.0,
            derived=True,
        ),
    ] = None
    acceleration_noise_pu: Annotated[
        Float | None,
        setting(
            "acceleration_noise_rad_s2 in per-unit of the machine's rated electrical "
            "acceleration n_p T_rated / J",
            gt=0.0,
            default_doc="unset: acceleration_noise_rad_s2",
        ),
    ] = None
    R2_drift_ohm_per_s: Annotated[
        Float | None,
        setting(
            "R2 process noise: drift-rate uncertainty; the absolute twin of R2_drift_pu",
            "ohm/s",
            gt=0.0,
            derived=True,
        ),
    ] = None
    R2_drift_pu: Annotated[
        Float | None,
        setting(
            "R2_drift_ohm_per_s in per-unit of R2 / T2, R2 per rotor time constant (the R2 "
            "error shows in the flux through the rotor's corner 1/T2; as mras.R1_rate_pu)",
            gt=0.0,
            default_doc="unset: R2_drift_ohm_per_s",
        ),
    ] = None
    current_noise_A: Annotated[
        Float | None,
        setting(
            "measurement noise per current component (rms); the absolute twin of current_noise_pu",
            "A",
            gt=0.0,
            derived=True,
        ),
    ] = None
    current_noise_pu: Annotated[
        Float | None,
        setting(
            "current_noise_A in per-unit of the machine's rated peak current (the sensors' "
            "range, and their noise, scale with it)",
            gt=0.0,
            default_doc="unset: current_noise_A",
        ),
    ] = None

    def records(self, ctx: EstimatorContext) -> EstimatorRecords:
        """Process and measurement noise (:func:`default_ekf_noise`).

        Parameters
        ----------
        ctx : EstimatorContext
            The controller's model and the drive.

        Returns
        -------
        EstimatorRecords
        """
        from imdrive.config.scaled import ekf_noise

        q, r, p0 = default_ekf_noise(
            ctx.Ts, ctx.sigma_L1_hat, ctx.psi0, ctx.R2_hat, *ekf_noise(self, ctx.scenario.machine)
        )
        on = ctx.scenario.estimator.R2_adaptation == "ekf"
        params = dict(
            q=q,
            r=r,
            p0=p0,
            estimate_R2=on,
            R2_min=0.5 * ctx.R2_hat,
            R2_max=2.0 * ctx.R2_hat,
            write_R2=on,
        )
        return EstimatorRecords(params)


def _noise(n: int):
    """The ``n``-th of :func:`imdrive.config.scaled.ekf_noise` (``EKF_NOISE``'s order)."""

    def value(sc) -> float:
        from imdrive.config.scaled import ekf_noise

        return ekf_noise(sc.ekf, sc.machine)[n]

    value.__qualname__ = f"_noise_{n}"
    return value


register_derived(
    Derived(
        "ekf.voltage_noise_V",
        "Table IV's 5 V scaled by the rated phase voltage's peak (0.0278 × it; config/scaled.py)",
        _noise(0),
        uses_estimator("ekf"),
    ),
    Derived(
        "ekf.flux_noise_Wb_per_s",
        "Table IV's 0.1 Wb/s scaled by psi_rated / T2 (0.0189 × it; config/scaled.py)",
        _noise(1),
        uses_estimator("ekf"),
    ),
    Derived(
        "ekf.acceleration_noise_rad_s2",
        "Table IV's 2000 rad/s² scaled by the rated acceleration n_p T_rated / J (5.56 × it; "
        "config/scaled.py)",
        _noise(2),
        uses_estimator("ekf"),
    ),
    Derived(
        "ekf.R2_drift_ohm_per_s",
        "Table IV's 0.5 ohm/s scaled by R2 / T2 (0.0536 × it; config/scaled.py)",
        _noise(3),
        uses_estimator("ekf"),
    ),
    Derived(
        "ekf.current_noise_A",
        "Table IV's 0.05 A scaled by the rated peak current (0.00436 × it; config/scaled.py)",
        _noise(4),
        uses_estimator("ekf"),
    ),
)
