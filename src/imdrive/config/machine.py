"""Induction machine parameters: the T-equivalent circuit (``MachineParams``) and the published
parameter sets (``config/data/machines.toml``).

The plant model these parameters feed, its state variables and equations, is documented in
:mod:`imdrive.kernels.machine`.
"""

from __future__ import annotations

import functools
import math
import tomllib
from dataclasses import asdict, fields, replace
from importlib import resources
from typing import Annotated

from imdrive.config.validation import Float, Int, Str, setting, settings
from imdrive.errors import ConfigError


@settings("machine")
class MachineParams:
    """T-equivalent-circuit parameters of a three-phase induction machine (per phase, SI).

    Attributes
    ----------
    R1_ohm, R2_ohm : float
        Stator and (stator-referred) rotor resistance at the reference temperature, ohm.
    Ll1_H, Ll2_H : float
        Stator and rotor leakage inductance, H.
    M_H : float
        Magnetising (mutual) inductance, H.
    pole_pairs : int
        Number of pole pairs n_p.
    J_kgm2 : float
        Moment of inertia of rotor and load, kg m^2.
    B_Nms : float
        Viscous friction coefficient, N m s/rad.
    rated_power_W, rated_voltage_V, rated_frequency_Hz : float
        Nameplate (shaft power, line-to-line rms voltage, frequency).
    description : str
        Free text.
    """

    R1_ohm: Annotated[
        Float, setting("stator resistance at the reference temperature", "ohm", gt=0.0)
    ]
    R2_ohm: Annotated[
        Float,
        setting(
            "rotor resistance (referred to the stator) at the reference temperature", "ohm", gt=0.0
        ),
    ]
    Ll1_H: Annotated[Float, setting("stator leakage inductance", "H", gt=0.0)]
    Ll2_H: Annotated[Float, setting("rotor leakage inductance", "H", gt=0.0)]
    M_H: Annotated[Float, setting("magnetising (mutual) inductance", "H", gt=0.0)]
    pole_pairs: Annotated[
        Int,
        setting("number of pole pairs n_p (<= 100: more than any machine built)", ge=1, le=100),
    ] = 2
    J_kgm2: Annotated[Float, setting("moment of inertia of rotor and load", "kg m²", gt=0.0)] = (
        0.069
    )
    B_Nms: Annotated[Float, setting("viscous friction of the machine", "N m s/rad", ge=0.0)] = 0.0
    rated_power_W: Annotated[
        Float,
        setting("nameplate shaft power: scales the current limits", "W", gt=0.0),
    ] = 2238.0
    rated_voltage_V: Annotated[
        Float,
        setting(
            "nameplate line-to-line rms voltage: scales the rated flux and current", "V", gt=0.0
        ),
    ] = 220.0
    rated_frequency_Hz: Annotated[
        Float, setting("nameplate frequency: scales the rated flux", "Hz", gt=0.0)
    ] = 60.0
    description: Annotated[Str, setting("free text")] = ""

    # derived quantities -------------------------------------------------------------------
    @property
    def L1_H(self) -> float:
        """Stator self-inductance L1 = Ll1 + M, H."""
        return self.Ll1_H + self.M_H

    @property
    def L2_H(self) -> float:
        """Rotor self-inductance L2 = Ll2 + M, H."""
        return self.Ll2_H + self.M_H

    @property
    def sigma(self) -> float:
        """Leakage factor sigma = 1 - M^2 / (L1 L2)."""
        return 1.0 - self.M_H**2 / (self.L1_H * self.L2_H)

    @property
    def T2_s(self) -> float:
        """Rotor time constant T2 = L2 / R2, s."""
        return self.L2_H / self.R2_ohm

    @property
    def rated_flux_Wb(self) -> float:
        """Rotor flux of the machine at rated voltage and frequency, no load, Wb.

        ``(M/L1) * V_phase_peak / w_e`` with ``V_phase_peak = sqrt(2/3) V_ll``.
        """
        v_peak = math.sqrt(2.0 / 3.0) * self.rated_voltage_V
        return self.M_H / self.L1_H * v_peak / (2 * math.pi * self.rated_frequency_Hz)

    @property
    def rated_current_A(self) -> float:
        """Nominal peak phase current, A: rated power over sqrt(3) V_ll, as a peak value.

        Used only to scale limits (controller current limit, divergence bound).
        """
        return math.sqrt(2.0) * self.rated_power_W / (math.sqrt(3.0) * self.rated_voltage_V)

    def with_(self, **changes) -> MachineParams:
        """Return a copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            Field name -> new value, in the fields' units.

        Returns
        -------
        MachineParams
            The new, validated parameter set.
        """
        return replace(self, **changes)

    def to_dict(self) -> dict:
        """The fields as a plain dictionary.

        Returns
        -------
        dict
            Field name -> value, in the fields' units.
        """
        return asdict(self)


@functools.cache
def _presets_toml() -> dict[str, dict]:
    text = resources.files("imdrive.config").joinpath("data/machines.toml").read_text()
    return tomllib.loads(text)


def _load_presets() -> dict[str, dict]:
    """The machine parameter sets of ``data/machines.toml`` (a fresh copy: callers may edit)."""
    return {name: dict(table) for name, table in _presets_toml().items()}


def preset_table(name: str) -> dict:
    """The ``[machine]`` values of preset ``name`` (MachineParams fields, no ``source``)."""
    presets = _presets_toml()
    if name not in presets:
        raise ConfigError("machine.preset", f"unknown preset {name!r}; known: {sorted(presets)}")
    return {k: v for k, v in presets[name].items() if k != "source"}


def machine_presets() -> dict[str, str]:
    """Names and descriptions of the published machine parameter sets.

    Returns
    -------
    dict of str to str
        Preset name -> its description.
    """
    return {k: v.get("description", "") for k, v in _load_presets().items()}


def machine_preset(name: str = "paper-table-iv", **overrides) -> MachineParams:
    """A published machine parameter set, optionally with fields overridden.

    ``paper-table-iv`` (the paper's Table IV, J = 0.069 kg m^2) and ``krause-3hp`` (the textbook
    machine it comes from, J = 0.089 kg m^2).

    Parameters
    ----------
    name : str
        A name of :func:`machine_presets`.
    **overrides
        Field name -> value replacing the preset's (e.g. ``J_kgm2=0.1``), in the fields' units.

    Returns
    -------
    MachineParams
        The validated parameter set.
    """
    data = preset_table(name)
    known = {f.name for f in fields(MachineParams)}
    for k in overrides:
        if k not in known:
            raise ConfigError(f"machine.{k}", "unknown field")
    data.update(overrides)
    return MachineParams(**data)
