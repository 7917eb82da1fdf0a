"""The R2 laws' settings half: the registry of their settings classes.

An R2 law turns the detected flux error of a decision window into the controller's R2_hat.
Its settings class is registered here under the value of ``compensator.step_law`` that selects
it and the scenario section that holds its keys; the scenario gets one section per registered
law (as it does per estimator, :func:`imdrive.config.registry.package_sections`). The paper's
table law (``"table"``) keeps its keys in ``[compensator]`` (and so would ``"adaptive"``, a
deprecated value that runs as ``"kalman"``); a model-based law is its kernel module, its
settings class and its tests.
"""

from __future__ import annotations

#: ``{step_law name: settings class}`` of the laws with a section of their own.
R2_LAW_SETTINGS: dict[str, type] = {}

#: The laws whose settings live in ``[compensator]`` (the fuzzy table's).
FUZZY_LAWS = ("table", "adaptive")


def r2_law(name: str, section: str, description: str):
    """Class decorator: register an R2 law's settings class.

    Parameters
    ----------
    name : str
        The ``compensator.step_law`` value that selects the law.
    section : str
        Its scenario section (``[section]``).
    description : str
        One line for the section's documentation.
    """

    def wrap(cls):
        cls.law_name = name
        cls.law_section = section
        cls.law_description = description
        R2_LAW_SETTINGS[name] = cls
        return cls

    return wrap


def law_sections() -> dict[str, type]:
    """``{section: settings class}`` of every registered R2 law, in registration order."""
    return {c.law_section: c for c in R2_LAW_SETTINGS.values()}


def law_names() -> tuple[str, ...]:
    """Every value ``compensator.step_law`` accepts."""
    return (*FUZZY_LAWS, *R2_LAW_SETTINGS)
