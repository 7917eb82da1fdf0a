"""The R2 laws' settings half: the registry of their settings classes.

An R2 law turns the detected flux error of a decision window into the controller's R2_hat.
Its settings class is registered here under the value of ``compensator.step_law`` that selects
it and the scenario section that holds its keys; the scenario gets one section per registered
law (as it does per estimator, :func:`imdrive.config.registry.package_sections`). The paper's
table law (``"table"``) keeps its keys in ``[compensator]`` (and so would ``"adaptive"``, a
deprecated value that runs as ``"kalman"``); a model-based law is its kernel module, its
settings class and its tests.

A law outside the package (a plug-in, :mod:`imdrive.kernels.r2_law_registry`) registers its
settings class here with no section: its keys are the table ``[plugins.settings.NAME]``, and
the class builds the law's records (``records(ctx) -> LawRecords``) from a :class:`LawContext`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from imdrive.config.validation import settings

#: ``{step_law name: settings class}`` of the laws with a section of their own.
R2_LAW_SETTINGS: dict[str, type] = {}

#: The laws whose settings live in ``[compensator]`` (the fuzzy table's).
FUZZY_LAWS = ("table", "adaptive")


@dataclass(frozen=True)
class LawContext:
    """What a plug-in law's record builder may use besides its own settings.

    Attributes
    ----------
    scenario : Scenario
        The whole scenario.
    R2_hat : float
        The controller's R2_hat at the start, ohm.
    T : float
        The compensator's decision period, s.
    R2_min, R2_max : float
        The clamps of R2_hat, ohm.
    """

    scenario: object
    R2_hat: float
    T: float
    R2_min: float
    R2_max: float


@dataclass(frozen=True)
class LawRecords:
    """A plug-in law's records as field values: ``params`` and the initial ``state`` (unset
    fields are zero; a name the record lacks is refused)."""

    params: dict
    state: dict = field(default_factory=dict)


def r2_law(name: str, section: str | None, description: str, *, log_units: dict | None = None):
    """Class decorator: register an R2 law's settings class.

    Parameters
    ----------
    name : str
        The ``compensator.step_law`` value that selects the law.
    section : str or None
        Its scenario section (``[section]``) for a law of the package; ``None`` for a plug-in
        law, whose class is then made the validated table ``[plugins.settings.NAME]`` and
        must define ``records(self, ctx: LawContext) -> LawRecords``.
    description : str
        One line for the section's documentation.
    log_units : dict, optional
        ``{log field: (unit, scale)}`` for each log field a plug-in law's kernel adds (the
        exported column is ``f"{field}_{unit}"``, the value times ``scale``).
    """

    def wrap(cls):
        if section is None:
            if not callable(getattr(cls, "records", None)):
                raise TypeError(f"R2 law settings class {cls.__name__} must define records(ctx)")
            cls = settings(f"plugins.settings.{name}")(cls)
        cls.law_name = name
        cls.law_log_units = dict(log_units or {})
        cls.law_section = section
        cls.law_description = description
        R2_LAW_SETTINGS[name] = cls
        return cls

    return wrap


def law_sections() -> dict[str, type]:
    """``{section: settings class}`` of every registered R2 law of the package (those with a
    section), in registration order."""
    return {c.law_section: c for c in R2_LAW_SETTINGS.values() if c.law_section}


def plugin_law(name: str):
    """The settings class of plug-in law ``name``, or None (not a plug-in law)."""
    cls = R2_LAW_SETTINGS.get(name)
    return cls if cls is not None and cls.law_section is None else None


def law_names() -> tuple[str, ...]:
    """Every value ``compensator.step_law`` accepts."""
    return (*FUZZY_LAWS, *R2_LAW_SETTINGS)
