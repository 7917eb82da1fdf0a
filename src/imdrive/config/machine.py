"""Induction machine parameters: the T-equivalent circuit and nameplate (``MachineParams``), the
published parameter sets (``config/data/machines.toml``), a user's own parameter file
(``[machine] file = "my-motor.toml"``). The rated operating point and the nameplate checks
are in :mod:`imdrive.config.rated` (served here as well: :func:`rated_point`).

The plant model these parameters feed, its state variables and equations, is documented in
:mod:`imdrive.kernels.machine`. The steady state used here for the rated point and the
nameplate checks is the T-equivalent circuit of :mod:`imdrive.analysis.circuit` (the same
equations, written with Python's complex numbers so that this layer needs no numpy).
"""

from __future__ import annotations

import functools
import math
import tomllib
import warnings
from dataclasses import asdict, fields, replace
from importlib import resources
from pathlib import Path
from typing import Annotated

from pydantic import model_validator

from imdrive.config.validation import Float, Int, Str, setting, settings
from imdrive.errors import ConfigError, ConfigWarning

#: Keys of a parameter set in ``data/machines.toml`` (or a user's file) that are not
#: :class:`MachineParams` fields: where the numbers come from, and notes on them.
METADATA_KEYS = ("source", "notes")


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
    rated_speed_rpm, rated_torque_Nm, rated_current_rms_A : float or None
        Nameplate speed, shaft torque and line current (rms); ``None``: derived
        (:func:`rated_point` says how).
    rated_power_factor, rated_efficiency : float or None
        Nameplate power factor and efficiency at rated load, dimensionless; ``None``:
        derived.
    file : str or None
        A TOML file of ``[machine]`` values, loaded when a scenario (or
        :func:`machine_preset`) is read: its values lie over the preset's, and the
        scenario's own ``[machine]`` keys over both.
    description : str
        Free text.

    Notes
    -----
    A nameplate that contradicts the circuit is refused with a one-line
    :class:`~imdrive.errors.ConfigError` naming the fields: a rated speed at or above the
    synchronous speed ``60 f / n_p``, a rated torque at or above the circuit's breakdown
    torque at rated voltage and frequency, a rated current at or below the circuit's no-load
    (magnetising) current at rated voltage. A suspicious one gets a
    :class:`~imdrive.errors.ConfigWarning`: a rated slip above 10 %, a rated power factor
    outside 0.5-0.95, a rated torque that is not ``P / w_m`` within 5 %, a rated current that
    is not ``P / (sqrt(3) V eta cos phi)`` within 10 %, a rated power the circuit cannot
    deliver at rated voltage.
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
    rated_speed_rpm: Annotated[
        Float | None,
        setting(
            "nameplate speed at rated load",
            "rpm",
            default_doc="P / T_rated if rated_torque_Nm is given, else the circuit's speed "
            "where it delivers rated_power_W",
            gt=0.0,
        ),
    ] = None
    rated_torque_Nm: Annotated[
        Float | None,
        setting(
            "nameplate shaft torque at rated load",
            "N m",
            default_doc="rated_power_W / (2 pi rated_speed_rpm / 60)",
            gt=0.0,
        ),
    ] = None
    rated_current_rms_A: Annotated[
        Float | None,
        setting(
            "nameplate line current at rated load (rms)",
            "A",
            default_doc="P / (sqrt(3) V eta cos phi) if both are given, else the circuit's "
            "current at rated torque",
            gt=0.0,
        ),
    ] = None
    rated_power_factor: Annotated[
        Float | None,
        setting(
            "nameplate power factor at rated load",
            default_doc="the circuit's at rated torque",
            gt=0.0,
            le=1.0,
        ),
    ] = None
    rated_efficiency: Annotated[
        Float | None,
        setting(
            "nameplate efficiency at rated load",
            default_doc="the circuit's at rated torque (copper losses only)",
            gt=0.0,
            le=1.0,
        ),
    ] = None
    file: Annotated[
        Str | None,
        setting(
            "a TOML file of [machine] values (path relative to the scenario file; to the "
            "working directory for --set): over the preset's values, under this table's",
            default_doc="none",
        ),
    ] = None
    description: Annotated[Str, setting("free text")] = ""

    @model_validator(mode="after")
    def _leakage_resolved(self):
        """The leakage factor must survive the sums that make L1 and L2 (see
        :func:`check_leakage_factor`)."""
        check_leakage_factor(self.Ll1_H, self.Ll2_H, self.M_H, "M_H")
        return self

    @model_validator(mode="after")
    def _nameplate_rules(self):
        """The nameplate against the circuit: contradictions refused, oddities warned (once
        per distinct circuit and nameplate: a sweep that varies the load costs nothing)."""
        from imdrive.config.rated import nameplate_findings

        for field, rule in nameplate_findings(self):
            warnings.warn(ConfigWarning(field, rule), stacklevel=2)
        return self

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
        """Scale of the current limits, A: ``sqrt(2) P / (sqrt(3) V_ll)`` (a peak value).

        Used only to scale limits (controller current limit ``2 x``, divergence bound
        ``100 x``), and kept as it is so that every run stays as it was. It is not the
        nameplate current: that one also divides by efficiency and power factor (about 25 %
        more); see :func:`rated_point` ``current_rms_A``.
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


#: Smallest leakage factor a machine may have. Real machines have 0.02 to 0.2; below 1e-9 the
#: leakage inductances are lost in L1 = Ll1 + M (a float carries 16 digits) and sigma L1, a
#: divisor of the current model and of the controller, comes out 0.
SIGMA_MIN = 1e-9


def check_leakage_factor(Ll1: float, Ll2: float, M: float, field: str) -> float:
    """The leakage factor ``sigma = 1 - M^2 / (L1 L2)`` of ``Ll1``, ``Ll2``, ``M`` (H),
    refused below :data:`SIGMA_MIN` with a :class:`ConfigError` naming ``field``.

    Parameters
    ----------
    Ll1, Ll2, M : float
        Stator and rotor leakage inductances and the magnetising inductance, H.
    field : str
        The field the error names (relative to the table being validated).

    Returns
    -------
    float
        sigma.
    """
    L1, L2 = Ll1 + M, Ll2 + M
    sigma = 1.0 - (M / L1) * (M / L2)  # no M**2: it overflows before M does
    if not sigma >= SIGMA_MIN:
        raise ConfigError(
            field,
            f"the leakage factor sigma = 1 - M^2/(L1 L2) is {sigma:.3g} (below {SIGMA_MIN:g}): "
            "the leakage inductances vanish against M",
        )
    return sigma


@functools.cache
def _presets_toml() -> dict[str, dict]:
    text = resources.files("imdrive.config").joinpath("data/machines.toml").read_text()
    return tomllib.loads(text)


def _load_presets() -> dict[str, dict]:
    """The machine parameter sets of ``data/machines.toml`` (a fresh copy: callers may edit)."""
    return {name: dict(table) for name, table in _presets_toml().items()}


def preset_table(name: str) -> dict:
    """The ``[machine]`` values of preset ``name`` (MachineParams fields, no metadata)."""
    presets = _presets_toml()
    if name not in presets:
        raise ConfigError("machine.preset", f"unknown preset {name!r}; known: {sorted(presets)}")
    return {k: v for k, v in presets[name].items() if k not in METADATA_KEYS}


def preset_source(name: str) -> str:
    """The publication (book or paper, table) preset ``name`` was taken from."""
    preset_table(name)  # the error for an unknown name
    return _presets_toml()[name].get("source", "")


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

    ``imdrive presets`` lists them (``paper-table-iv``, the paper's Table IV with
    J = 0.069 kg m^2; ``krause-3hp``, the textbook machine it comes from; the other sets of
    ``config/data/machines.toml``, ``docs/machines.md``).

    Parameters
    ----------
    name : str
        A name of :func:`machine_presets`.
    **overrides
        Field name -> value replacing the preset's (e.g. ``J_kgm2=0.1``), in the fields' units.
        ``file="my-motor.toml"`` loads a parameter file (relative to the working directory)
        between the preset and the other overrides.

    Returns
    -------
    MachineParams
        The validated parameter set.
    """
    if not isinstance(name, str):  # a list or a table would be an unhashable key below
        raise ConfigError("name", f"must be a preset name (a str), got {type(name).__name__}")
    known = {f.name for f in fields(MachineParams)}
    for k in overrides:
        if k not in known:
            raise ConfigError(f"machine.{k}", "unknown field")
    if not overrides:
        return _preset_as_is(name)
    return MachineParams(**machine_table(name, overrides))


@functools.lru_cache(maxsize=64)
def _preset_as_is(name: str) -> MachineParams:
    # a parameter set is frozen: one validated instance serves every caller (the per-unit
    # defaults compare with Table IV's about 25 times per scenario built)
    return MachineParams(**machine_table(name, {}))


# ------------------------------------------------------------------------------------------
# a user's parameter file: [machine] file = "my-motor.toml"


def machine_table(preset: str, table: dict) -> dict:
    """The ``[machine]`` values of a scenario: the preset's, then its ``file``'s, then its own.

    Parameters
    ----------
    preset : str
        The parameter set the machine starts from (``machine.preset``).
    table : dict
        The scenario's other ``[machine]`` keys; ``file`` (if any) names a TOML file read by
        :func:`machine_file_values` (a relative path is taken from the working directory:
        :meth:`~imdrive.config.scenario.Scenario.read` makes a scenario file's own relative
        paths absolute first, :func:`resolve_machine_file`).

    Returns
    -------
    dict
        MachineParams field -> value, not yet validated.
    """
    data = preset_table(preset)
    file = table.get("file")
    if file is not None:
        data |= machine_file_values(file, preset)
    return data | dict(table)


def resolve_machine_file(data: dict, base_dir) -> None:
    """Make a scenario file's relative ``[machine] file`` path absolute, from ``base_dir``.

    Called on the file's own text before any ``--set`` is applied, so an override's path
    stays relative to the working directory.

    Parameters
    ----------
    data : dict
        The TOML-shaped scenario as read (changed in place).
    base_dir : str or pathlib.Path or None
        The scenario file's folder; ``None`` leaves the path as it is.
    """
    machine = data.get("machine")
    if base_dir is None or not isinstance(machine, dict):
        return
    file = machine.get("file")
    if isinstance(file, str) and file and not Path(file).is_absolute():
        machine["file"] = str(Path(base_dir).resolve() / file)


def machine_file_values(file, preset: str = "paper-table-iv") -> dict:
    """The machine values of a user's TOML file, checked key by key.

    The file holds MachineParams fields, at its top level or under a ``[machine]`` table (as
    ``imdrive show PRESET`` and ``imdrive machine-from-nameplate`` write them), optionally
    ``preset = "NAME"`` (the set its values start from) and ``source``/``notes`` (text).

    Parameters
    ----------
    file : str
        Its path.
    preset : str
        The scenario's preset, to check the values against when the file names none.

    Returns
    -------
    dict
        Field -> value (with the file's preset's values below its own).

    Raises
    ------
    ConfigError
        ``machine.file`` for a missing or unreadable file or invalid TOML; ``machine.KEY`` for
        an unknown key or a value that breaks a rule (the message names the file).
    """
    if not isinstance(file, str) or not file:
        raise ConfigError("machine.file", f"must be a non-empty string (a path), got {file!r}")
    from imdrive.config.presets import MAX_TOML_BYTES
    from imdrive.config.user_files import read_user_text, redact, strange_keys

    text = read_user_text(file, "machine.file", MAX_TOML_BYTES, "machine file")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError("machine.file", f"{file} is not valid TOML: {exc}") from None
    except RecursionError:
        raise ConfigError("machine.file", f"{file}: TOML nested too deeply to read") from None
    has_table = "machine" in data
    if has_table:
        extra = sorted(set(data) - {"machine"})
        if extra or not isinstance(data["machine"], dict):
            raise ConfigError(
                "machine.file",
                f"{file}: a [machine] table and nothing else, or the keys at the top level "
                f"(found {extra[0] if extra else 'machine = a value'})",
            )
        data = data["machine"]
    settings_ = {f.name for f in fields(MachineParams)} - {"file"}
    known = settings_ | {"preset", *METADATA_KEYS}
    unknown = [k for k in data if k not in known]
    typos, n_foreign = strange_keys(unknown, known)
    if n_foreign and not has_table and not set(data) & settings_:
        # no [machine] table, no machine setting: not a machine file (a credentials file, a
        # colleague's configuration of something else); neither its keys nor values printed
        raise ConfigError(
            "machine.file",
            f"{file} is not an imdrive machine file: none of its {len(data)} keys is a machine "
            "setting (it holds MachineParams fields such as R1_ohm, at its top level or under "
            "[machine])",
        )
    if unknown:
        raise ConfigError(f"machine.{unknown[0]}", f"unknown key (in machine.file {file})")
    values = {k: v for k, v in data.items() if k not in METADATA_KEYS}
    base = values.pop("preset", preset)
    try:
        if not isinstance(base, str):
            raise ConfigError("machine.preset", "must be a string")
        values = preset_table(base) | values
        MachineParams(**values)
    except ConfigError as exc:  # the rule, without the file's text values
        raise ConfigError(exc.field, f"{redact(exc.rule, data)} (in machine.file {file})") from None
    return values


# the rated point and the nameplate checks live in imdrive.config.rated; their names are
# served here as well (this module's import path for them)
from imdrive.config.rated import (  # noqa: E402, F401
    POWER_FACTOR_WARN,
    SLIP_WARN,
    RatedPoint,
    check_nameplate,
    rated_point,
    rated_point_comment,
)
