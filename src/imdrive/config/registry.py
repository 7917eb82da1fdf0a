"""The estimators' settings half: the registry of their settings classes.

A speed estimator's settings class is its Python half (:mod:`imdrive.config.estimators` has
the package's): besides its validated settings it says how they and the controller's machine
model become the estimator's records (:class:`EstimatorRecords`, from an
:class:`EstimatorContext`). :func:`estimator_settings` registers it under the name
``control.speed_feedback`` selects; the compiled half is registered under the same name in
:mod:`imdrive.kernels.estimators.registry`, and :mod:`imdrive.run.estimators` joins the two.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Annotated

from imdrive.config.validation import Bool, setting, settings

#: The setting of the estimators whose adjustable model is the rotor current model
#: (``[mras]``, ``[smo_mras]``): what current it is fed over a control period.
PeriodMeanCurrent = Annotated[
    Bool,
    setting(
        "feed the current model the stator current's mean over the control period: the "
        "mean of its two samples plus the bend the turning back-emf gives it "
        "(kernels/estimators/common.py period_mean_offset; without it the estimate is "
        "off by 1.9 rpm at twice the rated speed and full load on Table IV)"
    ),
]


@dataclass(frozen=True)
class EstimatorContext:
    """What an estimator's record builder may use besides its own settings.

    Attributes
    ----------
    scenario : Scenario
        The whole scenario (for settings of other sections, e.g. ``flux_injection``).
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
        Parameter record fields by name (a name the record lacks is refused).
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


#: ``control.speed_feedback`` value -> the estimator's settings class
ESTIMATOR_SETTINGS: dict[str, type] = {}


def estimator_settings(
    name: str,
    section: str | None = None,
    *,
    log_units: dict | None = None,
    flux_error: bool = False,
    description: str = "",
    legend: str = "",
):
    """Class decorator: the settings class of speed estimator ``name`` (its Python half).

    The class is made a validated settings table (as every section) and registered, with the
    class attributes ``estimator_name``, ``estimator_section``, ``estimator_log_units``,
    ``estimator_flux_error``, ``estimator_description`` and ``estimator_legend``. It must define
    ``records(self, ctx: EstimatorContext) -> EstimatorRecords``, its gain design.

    Parameters
    ----------
    name : str
        The ``control.speed_feedback`` value that selects the estimator.
    section : str, optional
        The scenario section of a package estimator (``"mras"``); ``None`` for an estimator
        outside the package, whose table is ``[plugins.settings.NAME]``.
    log_units : dict, optional
        ``{log field: (unit, scale)}`` for each log field the estimator's kernel adds (the
        exported column is ``f"{field}_{unit}"``, the value times ``scale``).
    flux_error : bool
        Whether its step returns the rotor-flux error the R2 compensator and the injection
        need.
    description : str
        One line, for lists.
    legend : str
        Its short name in figure legends ("MRAS"); default the description without a
        trailing " speed estimator", else ``name``.

    Returns
    -------
    callable
        The decorator.
    """

    def wrap(cls):
        if not callable(getattr(cls, "records", None)):
            raise TypeError(f"estimator settings class {cls.__name__} must define records(ctx)")
        cls = settings(section or f"plugins.settings.{name}")(cls)
        cls.estimator_name = name
        cls.estimator_section = section
        cls.estimator_log_units = dict(log_units or {})
        cls.estimator_flux_error = flux_error
        doc = description or (cls.__doc__ or name).strip().splitlines()[0]
        cls.estimator_description = doc
        cls.estimator_legend = legend or doc.removesuffix(" speed estimator") or name
        ESTIMATOR_SETTINGS[name] = cls
        return cls

    return wrap


def package_sections() -> dict[str, type]:
    """``{section: settings class}`` of every estimator with a scenario section of its own
    (the package's), the MRAS first, then in registration order; each is a field of the
    scenario, so a new estimator of the package is its settings class here and no more."""
    out = {c.estimator_section: c for c in ESTIMATOR_SETTINGS.values() if c.estimator_section}
    return {k: out[k] for k in sorted(out, key=lambda k: k != "mras")}


def estimator_names() -> tuple[str, ...]:
    """Every value ``control.speed_feedback`` accepts: ``"measured"`` and each estimator."""
    return ("measured", *ESTIMATOR_SETTINGS)
