"""Voltage-source inverter.

The inverter turns the controller's voltage reference (held over one control period) into the
voltage the machine sees during that period, as a sequence of *segments* ``(duration, v_ab)``.
The average-value model returns one segment: the reference limited to the linear range of
space-vector modulation, ``|v| <= Vdc/sqrt(3)``, direction kept. A switching model (SVPWM with
dead time) returns up to seven segments per period from the same arguments, so the engine and
every controller stay unchanged when one is added.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from imdrive.errors import ConfigError

INVERTER_MODELS = ("average",)


@dataclass(frozen=True)
class InverterParams:
    """DC-link voltage-source inverter.

    Parameters
    ----------
    Vdc_V : float
        DC-link voltage, V. Default ``220*sqrt(2)``: a diode rectifier on a 220 V line.
    model : str
        ``"average"``: average-value model with the SVM voltage limit.
    """

    Vdc_V: float = 220.0 * math.sqrt(2.0)
    model: str = "average"

    def __post_init__(self):
        if isinstance(self.Vdc_V, bool) or not isinstance(self.Vdc_V, int | float):
            raise ConfigError("inverter.Vdc_V", "must be a number")
        if not math.isfinite(self.Vdc_V) or self.Vdc_V <= 0:
            raise ConfigError("inverter.Vdc_V", f"must be > 0 (got {self.Vdc_V})")
        if self.model not in INVERTER_MODELS:
            raise ConfigError("inverter.model", f"must be one of {sorted(INVERTER_MODELS)}")

    @property
    def v_max_V(self) -> float:
        """Largest voltage space vector in the linear SVM range, Vdc/sqrt(3), V."""
        return self.Vdc_V / math.sqrt(3.0)
