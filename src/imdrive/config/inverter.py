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
import typing
from typing import Annotated, Literal

from imdrive.config.validation import Float, setting, settings

InverterModel = Literal["average"]
INVERTER_MODELS = typing.get_args(InverterModel)


@settings("inverter")
class InverterParams:
    """DC-link voltage-source inverter (``[inverter]``).

    Parameters
    ----------
    Vdc_V : float
        DC-link voltage, V. Default ``220*sqrt(2)``: a diode rectifier on a 220 V line.
    model : str
        ``"average"``: average-value model with the SVM voltage limit.
    """

    Vdc_V: Annotated[
        Float,
        setting(
            "DC-link voltage; the largest voltage vector is Vdc/√3",
            "V",
            gt=0.0,
            default_doc="220·√2 ≈ 311.1 (a diode rectifier on a 220 V line)",
        ),
    ] = 220.0 * math.sqrt(2.0)
    model: Annotated[
        InverterModel,
        setting('"average": average-value model limited to the linear range of space-vector PWM'),
    ] = "average"

    @property
    def v_max_V(self) -> float:
        """Largest voltage space vector in the linear SVM range, Vdc/sqrt(3), V."""
        return self.Vdc_V / math.sqrt(3.0)
