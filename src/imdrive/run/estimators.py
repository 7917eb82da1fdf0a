"""Speed estimators, the Python half: settings -> records, and the registry users extend.

An estimator has two halves. Its compiled half (records and numba functions) is registered in
:mod:`imdrive.kernels.estimators.registry`; its Python half, here, says which scenario section
holds its settings, how those settings and the controller's machine model become its
parameter and initial-state records (the gain design), and the unit of each log field it
adds. :func:`register_estimator` joins the two under the name ``control.speed_feedback``
selects; the four estimators of the package are registered the same way (bottom of this
module), so the loop, the batch, the sweeps and the bench treat a user's estimator exactly as
theirs.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from imdrive.design.estimators import (
    afo_regeneration_gain,
    default_afo_gains,
    default_ekf_noise,
    default_reactive_mras_gains,
)
from imdrive.design.gains import default_mras_gains
from imdrive.errors import ConfigError
from imdrive.kernels.estimators import registry
from imdrive.kernels.estimators.registry import EstimatorKernel


@dataclass(frozen=True)
class EstimatorContext:
    """What an estimator's record builder may use besides its own settings.

    Attributes
    ----------
    scenario : Scenario
        The whole scenario (for settings of other sections, e.g. ``flux_injection``).
    settings : object
        The estimator's own settings section (``None`` if it has none).
    Ts : float
        Control period, s.
    psi0 : float
        Rotor-flux reference at the start, Wb.
    R1_hat, R2_hat, M_hat, L1_hat, L2_hat, sigma_L1_hat : float
        The controller's machine model, ohm and H.
    n_p : int
        Pole pairs.
    J : float
        The plant's inertia as configured, kg m².
    """

    scenario: object
    settings: object
    Ts: float
    psi0: float
    R1_hat: float
    R2_hat: float
    M_hat: float
    L1_hat: float
    L2_hat: float
    sigma_L1_hat: float
    n_p: int
    J: float


@dataclass(frozen=True)
class EstimatorRecords:
    """An estimator's records as field values, and what to report.

    Attributes
    ----------
    params : dict
        Parameter record fields by name (``new_record`` refuses a name the dtype lacks).
    state : dict
        Initial-state fields by name (unset fields are zero).
    derived : dict
        Derived quantities for ``summary.json`` (``name -> float``).
    sources : dict
        For each derived quantity, the setting it comes from (to name it in an error).
    """

    params: dict
    state: dict = field(default_factory=dict)
    derived: dict = field(default_factory=dict)
    sources: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Estimator:
    """A registered speed estimator: its compiled half and its Python half.

    Attributes
    ----------
    kernel : EstimatorKernel
        The compiled half (:func:`imdrive.kernels.estimators.registry.register_kernel`).
    section : str or None
        The scenario section holding its settings (``None``: no settings).
    records : callable
        ``records(ctx: EstimatorContext) -> EstimatorRecords``: the gain design.
    log_units : mapping
        ``{log field: (unit, scale)}`` for each of ``kernel.log_fields`` (the exported column
        is ``f"{field}_{unit}"``, the value times ``scale``).
    settings : type or None
        For an estimator outside the package: its settings class (a dataclass of
        ``imdrive.config`` settings, see :func:`register_estimator`).
    description : str
        One line for ``imdrive presets``/docs.
    """

    kernel: EstimatorKernel
    section: str | None
    records: Callable[[EstimatorContext], EstimatorRecords]
    log_units: Mapping[str, tuple[str, float]] = field(default_factory=dict)
    settings: type | None = None
    description: str = ""

    @property
    def name(self) -> str:
        """The ``control.speed_feedback`` value that selects it."""
        return self.kernel.name


_ESTIMATORS: dict[str, Estimator] = {}


def register_estimator(
    kernel: EstimatorKernel,
    records: Callable[[EstimatorContext], EstimatorRecords],
    *,
    section: str | None = None,
    settings: type | None = None,
    log_units: Mapping[str, tuple[str, float]] | None = None,
    description: str = "",
) -> Estimator:
    """Register a speed estimator under ``kernel.name`` and return it.

    Parameters
    ----------
    kernel : EstimatorKernel
        From :func:`imdrive.kernels.estimators.registry.register_kernel`.
    records : callable
        ``records(ctx) -> EstimatorRecords`` (its gain design).
    section : str, optional
        Scenario section of its settings.
    settings : type, optional
        Settings class of an estimator outside the package (the package's own estimators
        keep their sections in the scenario).
    log_units : mapping, optional
        ``{field: (unit, scale)}`` for each of ``kernel.log_fields``.
    description : str
        One line describing it.

    Returns
    -------
    Estimator

    Raises
    ------
    ValueError
        A log field without a unit.
    """
    units = dict(log_units or {})
    missing = [f for f in kernel.log_fields if f not in units]
    if missing:
        raise ValueError(f"estimator {kernel.name!r}: log fields without a unit: {missing}")
    est = Estimator(kernel, section, records, units, settings, description)
    _ESTIMATORS[kernel.name] = est
    return est


def estimator(name: str) -> Estimator:
    """The registered estimator ``name`` (``control.speed_feedback``; "measured": the MRAS)."""
    key = "mras" if name == "measured" else name
    try:
        return _ESTIMATORS[key]
    except KeyError:
        raise ConfigError(
            "control.speed_feedback",
            f'no estimator "{name}" is registered (known: "measured", '
            + ", ".join(f'"{n}"' for n in _ESTIMATORS)
            + ")",
        ) from None


def estimator_names() -> tuple[str, ...]:
    """Every registered estimator's name."""
    return tuple(_ESTIMATORS)


# --- the package's estimators: gain design ---------------------------------------------------


def _mras_records(ctx: EstimatorContext) -> EstimatorRecords:
    """Schauder's MRAS: K1, K2 from the bandwidth (:func:`default_mras_gains`)."""
    sc = ctx.scenario
    ms = sc.mras
    K1, K2 = default_mras_gains(ctx.psi0, ctx.L2_hat / ctx.R2_hat, 2 * math.pi * ms.bandwidth_Hz)
    K1 = ms.K1 if ms.K1 is not None else K1
    K2 = ms.K2 if ms.K2 is not None else K2
    normalise = ms.normalise if ms.normalise is not None else sc.control.field_weakening
    params = dict(
        wc=ms.wc_rad_s,
        K1=K1,
        K2=K2,
        k_R1=ms.R1_rate_per_s,
        R1_fmax=ms.R1_max_freq_Hz,
        R1_min=0.5 * ctx.R1_hat,
        R1_max=2.0 * ctx.R1_hat,
        psi2_norm=ctx.psi0 * ctx.psi0 if normalise else 0.0,
        R1_dc=ms.R1_standstill,
        # the flux build-up: four rotor time constants of the controller's model
        R1_dc_settle=4.0 * ctx.L2_hat / ctx.R2_hat,
    )
    src = {
        "mras_K1": "mras.K1" if ms.K1 is not None else "mras.bandwidth_Hz",
        "mras_K2": "mras.K2" if ms.K2 is not None else "mras.bandwidth_Hz",
    }
    return EstimatorRecords(params, derived={"mras_K1": K1, "mras_K2": K2}, sources=src)


def _reactive_mras_records(ctx: EstimatorContext) -> EstimatorRecords:
    """Reactive-power MRAS: K1, K2 from the bandwidth (:func:`default_reactive_mras_gains`)."""
    rm = ctx.scenario.reactive_mras
    K1, K2 = default_reactive_mras_gains(ctx.psi0, ctx.L2_hat, 2 * math.pi * rm.bandwidth_Hz)
    K1 = rm.K1 if rm.K1 is not None else K1
    K2 = rm.K2 if rm.K2 is not None else K2
    derived = {"reactive_mras_K1": K1, "reactive_mras_K2": K2}
    return EstimatorRecords(dict(K1=K1, K2=K2), derived=derived)


def _afo_records(ctx: EstimatorContext) -> EstimatorRecords:
    """Full-order observer: adaptation gains (:func:`default_afo_gains`), observer gain."""
    sc = ctx.scenario
    af = sc.afo
    Kp, Ki, k_R1, k_R2 = default_afo_gains(
        ctx.psi0,
        ctx.R1_hat,
        ctx.R2_hat,
        ctx.sigma_L1_hat,
        ctx.M_hat,
        ctx.L2_hat,
        af.g1_per_s,
        2 * math.pi * af.bandwidth_Hz,
        af.R1_bandwidth_rad_s,
        af.R2_bandwidth_rad_s,
        sc.flux_injection.amplitude,
        2 * math.pi * sc.flux_injection.frequency_Hz,
    )
    regen = af.gain == "regeneration"
    g2 = (
        afo_regeneration_gain(
            ctx.R1_hat, ctx.sigma_L1_hat, ctx.M_hat, ctx.L2_hat, af.g1_per_s, af.rho
        )
        if regen
        else af.g2_ohm
    )
    Kp = af.Kp if af.Kp is not None else Kp
    Ki = af.Ki if af.Ki is not None else Ki
    params = dict(
        gain_mode=1 if regen else 0,
        rho=af.rho,
        g1=af.g1_per_s,
        g2=af.g2_ohm,
        Kp=Kp,
        Ki=Ki,
        k_R1=k_R1 if af.R1_adaptation else 0.0,
        k_R2=k_R2 if sc.estimator.R2_adaptation == "afo" else 0.0,
        R_min=0.5,
        R_max=2.0,
    )
    derived = {"afo_Kp": Kp, "afo_Ki": Ki, "afo_g1_per_s": af.g1_per_s, "afo_g2_ohm": g2}
    return EstimatorRecords(params, derived=derived)


def _ekf_records(ctx: EstimatorContext) -> EstimatorRecords:
    """EKF: process and measurement noise (:func:`default_ekf_noise`)."""
    sc = ctx.scenario
    ek = sc.ekf
    q, r, p0 = default_ekf_noise(
        ctx.Ts,
        ctx.sigma_L1_hat,
        ctx.psi0,
        ctx.R2_hat,
        ek.voltage_noise_V,
        ek.flux_noise_Wb_per_s,
        ek.acceleration_noise_rad_s2,
        ek.R2_drift_ohm_per_s,
        ek.current_noise_A,
    )
    on = sc.estimator.R2_adaptation == "ekf"
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


_WB = ("Wb", 1.0)
register_estimator(
    registry.kernel("mras"),
    _mras_records,
    section="mras",
    log_units={f: _WB for f in ("lam_v_alpha", "lam_v_beta", "lam_i_alpha", "lam_i_beta")},
    description="Schauder's MRAS (rotor-flux reference and adjustable models)",
)
register_estimator(
    registry.kernel("reactive-mras"),
    _reactive_mras_records,
    section="reactive_mras",
    description="reactive-power MRAS (Peng & Fukao 1994)",
)
register_estimator(
    registry.kernel("afo"),
    _afo_records,
    section="afo",
    description="adaptive full-order observer (Kubota, Matsuse & Nakano 1993)",
)
register_estimator(
    registry.kernel("ekf"),
    _ekf_records,
    section="ekf",
    description="extended Kalman filter for speed and R2",
)
