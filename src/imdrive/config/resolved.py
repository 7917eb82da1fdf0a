"""The defaults that depend on the scenario as a whole, as one scenario resolves them: what
``imdrive show PRESET --all`` prints beside an unset setting (``Scenario.to_toml``).
"""

from __future__ import annotations

from imdrive.config.current_control import current_controller
from imdrive.config.field_weakening import field_weakening_on
from imdrive.config.mras_bandwidth import mras_bandwidth_Hz
from imdrive.config.speed_gain import speed_gain_flux_scaling


def resolved_defaults(sc) -> dict[str, object]:
    """Dotted key -> the value an unset scenario-dependent setting takes in ``sc``.

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    dict
        ``control.field_weakening`` (:func:`~imdrive.config.field_weakening.field_weakening_on`),
        ``control.current_controller``, ``control.speed_gain_flux_scaling``,
        ``mras.bandwidth_Hz`` (:func:`~imdrive.config.mras_bandwidth.mras_bandwidth_Hz`); empty for
        an open-loop drive.
    """
    if sc.drive.mode != "vector":
        return {}
    return {
        "control.field_weakening": field_weakening_on(sc),
        "control.current_controller": current_controller(sc),
        "control.speed_gain_flux_scaling": speed_gain_flux_scaling(sc),
        "mras.bandwidth_Hz": mras_bandwidth_Hz(sc),
    }
