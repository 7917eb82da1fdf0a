"""Voltage-source inverter settings (``[inverter]``); the models are in
:mod:`imdrive.kernels.inverter`.

``"average"``: the reference limited to the linear range of space-vector modulation,
``|v| <= Vdc/sqrt(3)``, with dead time and device drops in averaged form.
``"switching"``: a two-level bridge with a symmetric triangular carrier at the control period
(regular sampling, single update: ``Ts = 1/f_sw``), min-max zero-sequence injection, exact
switching instants, dead time and device drops.
"""

from __future__ import annotations

import math
import typing
from typing import Annotated, Literal

from pydantic import model_validator

from imdrive.config.validation import Float, setting, settings
from imdrive.errors import ConfigError

InverterModel = Literal["average", "switching"]
INVERTER_MODELS = typing.get_args(InverterModel)


@settings("inverter")
class InverterParams:
    """DC-link voltage-source inverter (``[inverter]``).

    Parameters
    ----------
    Vdc_V : float or None
        DC-link voltage, V. Unset (``None``): ``sqrt(2)`` times the machine's rated line
        voltage, a diode rectifier on the machine's own supply (the scenario fills it in).
    model : str
        ``"average"``: average-value model with the SVM voltage limit; ``"switching"``: the
        two-level bridge switched at ``switching_frequency_Hz``.
    switching_frequency_Hz : float
        Carrier frequency, Hz. The switching model needs ``Ts = 1/f_sw``.
    dead_time_s : float
        Dead time of every leg, s (< half a switching period).
    device_drop_V : float
        Forward drop of the conducting device, V.
    sign_band_A : float
        Current band over which the averaged dead-time error changes sign, A.
    """

    Vdc_V: Annotated[
        Float | None,
        setting(
            "DC-link voltage; the largest voltage vector is Vdc/√3",
            "V",
            gt=0.0,
            default_doc="√2 × machine.rated_voltage_V (a diode rectifier on the machine's rated "
            "line voltage; 311.1 V for the 220 V Table IV machine)",
        ),
    ] = None
    model: Annotated[
        InverterModel,
        setting(
            '"average": average-value model limited to the linear range of space-vector PWM; '
            '"switching": two-level bridge, exact switching instants'
        ),
    ] = "average"
    switching_frequency_Hz: Annotated[
        Float,
        setting(
            "carrier (switching) frequency; the switching model needs simulation.Ts_s = 1/f_sw",
            "Hz",
            gt=0.0,
        ),
    ] = 10_000.0
    dead_time_s: Annotated[
        Float, setting("dead time of each leg (< half a switching period)", "s", ge=0.0)
    ] = 0.0
    device_drop_V: Annotated[
        Float, setting("forward voltage drop of the conducting switch or diode", "V", ge=0.0)
    ] = 0.0
    sign_band_A: Annotated[
        Float | None,
        setting(
            "current band over which the averaged dead-time error (average model) and the "
            "dead-time compensation change sign linearly; the absolute twin of sign_band_pu",
            "A",
            gt=0.0,
            derived=True,
        ),
    ] = None
    sign_band_pu: Annotated[
        Float | None,
        setting(
            "sign_band_A in per-unit of the machine's rated peak current (instead of "
            "sign_band_A; config/perunit.py sign_band_A)",
            gt=0.0,
            default_doc="unset: sign_band_A",
        ),
    ] = None

    @model_validator(mode="after")
    def _dead_time_fits(self):
        if not self.dead_time_s < 0.5 / self.switching_frequency_Hz:
            raise ConfigError(
                "dead_time_s",
                f"must be < half a switching period, 0.5/switching_frequency_Hz = "
                f"{0.5 / self.switching_frequency_Hz:g} s (got {self.dead_time_s:g})",
            )
        return self

    @property
    def v_max_V(self) -> float:
        """Largest voltage space vector in the linear SVM range, Vdc/sqrt(3), V."""
        if self.Vdc_V is None:
            raise ValueError(
                "inverter.Vdc_V is unset: it follows the machine's rated voltage, filled in by "
                "the Scenario (read scenario.inverter.v_max_V)"
            )
        return self.Vdc_V / math.sqrt(3.0)
