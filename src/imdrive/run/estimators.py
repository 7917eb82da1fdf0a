"""Speed estimators: the two registered halves joined, and what a user needs to add one.

An estimator has two halves registered under one name, the value of
``control.speed_feedback`` that selects it:

* the compiled half -- parameter and state record dtypes, a numba ``step(p, model, s, inp)``
  returning ``(w_r_hat, e_dq0)``, optional log and finiteness functions, and optionally its
  states for the stability maps (a :class:`ReducedState`; :func:`to_frame` rotates a
  stationary-frame vector into the controller's frame) -- :func:`register_kernel`
  (:mod:`imdrive.kernels.estimators.registry` has the contract);
* the Python half -- a settings class whose ``records(ctx)`` turns its settings and the
  controller's machine model into the records' values (the gain design) --
  :func:`estimator_settings` (:mod:`imdrive.config.estimators`).

:func:`estimator` joins them; :func:`build_estimator` fills the records of a scenario's
estimator. The loop, the batch, the sweeps and the bench use nothing else, so an estimator
written in the user's own module (listed in the scenario's ``[plugins] modules``) runs
wherever the package's four do. ``docs/architecture.md`` has the recipe and
``docs/examples/06-own-estimator.ipynb`` a worked example.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from imdrive.config.estimators import (
    ESTIMATOR_SETTINGS,
    EstimatorContext,
    EstimatorRecords,
    estimator_settings,
)
from imdrive.config.plugins import import_plugins
from imdrive.config.validation import Bool, Float, Int, setting
from imdrive.errors import ConfigError
from imdrive.kernels.estimators import registry
from imdrive.kernels.estimators.common import to_frame
from imdrive.kernels.estimators.registry import (
    ESTIMATOR_INPUT,
    EstimatorKernel,
    ReducedState,
    register_kernel,
)
from imdrive.kernels.records import b1, c16, f8, i8, new_record, record_dtype

__all__ = [
    "ESTIMATOR_INPUT",
    "Bool",
    "Estimator",
    "EstimatorContext",
    "EstimatorKernel",
    "EstimatorRecords",
    "Float",
    "Int",
    "ReducedState",
    "b1",
    "build_estimator",
    "c16",
    "estimator",
    "estimator_names",
    "estimator_settings",
    "f8",
    "i8",
    "record_dtype",
    "register_kernel",
    "setting",
    "to_frame",
]


@dataclass(frozen=True)
class Estimator:
    """A registered speed estimator: its compiled half and its settings class.

    Attributes
    ----------
    kernel : EstimatorKernel
        Records and numba functions.
    settings : type
        Its settings class (:func:`estimator_settings`).
    """

    kernel: EstimatorKernel
    settings: type

    @property
    def name(self) -> str:
        """The ``control.speed_feedback`` value that selects it."""
        return self.kernel.name

    @property
    def log_units(self) -> dict:
        """``{log field: (unit, scale)}`` of the fields its kernel adds to the log."""
        return self.settings.estimator_log_units

    @property
    def description(self) -> str:
        """One line describing it."""
        return self.settings.estimator_description


def estimator(name: str) -> Estimator:
    """The registered estimator ``name`` ("measured": the MRAS, which runs beside it).

    Parameters
    ----------
    name : str
        A ``control.speed_feedback`` value.

    Returns
    -------
    Estimator

    Raises
    ------
    ConfigError
        No such estimator, or only one of its halves is registered (naming the missing call).
    """
    key = "mras" if name == "measured" else name
    cls = ESTIMATOR_SETTINGS.get(key)
    try:
        kernel = registry.kernel(key)
    except KeyError:
        kernel = None
    if cls is None and kernel is None:
        known = ", ".join(f'"{n}"' for n in estimator_names())
        raise ConfigError("control.speed_feedback", f"no estimator {name!r} (known: {known})")
    if kernel is None:
        raise ConfigError(
            "control.speed_feedback",
            f'estimator "{key}" has a settings class but no compiled half: call '
            f'register_kernel("{key}", ...) in its module',
        )
    if cls is None:
        raise ConfigError(
            "control.speed_feedback",
            f'estimator "{key}" has a compiled half but no settings class: decorate one with '
            f'@estimator_settings("{key}")',
        )
    unitless = sorted(set(kernel.log_fields) - set(cls.estimator_log_units))
    if unitless:
        raise ConfigError(
            "control.speed_feedback",
            f'estimator "{key}": log fields without a unit in estimator_settings(log_units=...): '
            f"{unitless}",
        )
    return Estimator(kernel, cls)


def estimator_names() -> tuple[str, ...]:
    """``"measured"`` and every estimator whose two halves are registered."""
    both = [n for n in ESTIMATOR_SETTINGS if n in registry.kernel_names()]
    return ("measured", *both)


def estimator_of(sc) -> Estimator:
    """The estimator of scenario ``sc``, importing its ``[plugins] modules`` first (a scenario
    unpickled in a worker process did not import them when it was read)."""
    if sc.plugins.modules:
        import_plugins(sc.plugins.modules)
    return estimator(sc.control.speed_feedback)


def build_estimator(
    sc, ctx: EstimatorContext, est: Estimator | None = None
) -> tuple[Estimator, np.ndarray, np.ndarray, EstimatorRecords]:
    """The scenario's estimator and its parameter and initial-state records.

    Parameters
    ----------
    sc : Scenario
        The scenario.
    ctx : EstimatorContext
        The controller's model and the drive.
    est : Estimator, optional
        The scenario's estimator when the caller has it (default: :func:`estimator_of`).

    Returns
    -------
    estimator : Estimator
    params, state : numpy.ndarray
        ``(1,)`` records of its (tagged) dtypes, filled by field name.
    records : EstimatorRecords
        What its ``records(ctx)`` returned (derived quantities and their sources).
    """
    est = estimator_of(sc) if est is None else est
    er = sc.estimator_settings().records(ctx)
    try:
        params = new_record(est.kernel.params, er.params)
        state = new_record(est.kernel.state, er.state)
    except KeyError as exc:
        raise ConfigError(
            "control.speed_feedback",
            f'estimator "{est.name}": its records() names a field its record lacks: {exc}',
        ) from None
    return est, params, state, er
