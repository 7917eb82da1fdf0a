"""Scenarios: a whole run described by frozen dataclasses, read from and written to TOML.

A scenario file has a table per section of :class:`Scenario` (``[machine]``, ``[plant]``,
``[plant.thermal]``, ``[control]``, ...; :data:`SECTIONS`), every key optional. The settings
classes (one module per domain: :mod:`~imdrive.config.plant`, :mod:`~imdrive.config.control`,
:mod:`~imdrive.config.estimators`, :mod:`~imdrive.config.compensator`,
:mod:`~imdrive.config.sensors`, :mod:`~imdrive.config.simulation`, :mod:`~imdrive.config.output`)
are the one description of those keys: their fields carry type, rule, default,
unit and meaning, from which validation, ``--set`` paths (:mod:`imdrive.config.overrides`),
``docs/scenarios.md`` and the JSON Schema (:mod:`imdrive.config.docs`) all follow.
``imdrive show PRESET`` prints complete examples.

Profiles are written as in :mod:`imdrive.config.profiles`. Unknown keys, wrong types and
values that break a rule raise :class:`~imdrive.errors.ConfigError` naming the field, whether
the scenario comes from a file (:meth:`Scenario.from_dict`) or is built in Python (the classes'
constructors, ``dataclasses.replace``).
"""

from __future__ import annotations

from dataclasses import fields, replace
from os import PathLike
from pathlib import Path
from typing import Annotated

from pydantic import model_validator

from imdrive.config.checks import (
    compensator_rules,
    drive_mode_given,
    machine_defaults,
    per_unit_warnings,
    plugin_rules,
)
from imdrive.config.commissioning_ideal import resolve_ideal
from imdrive.config.compensator import (
    CompensatorSettings,
    InjectionSettings,
)
from imdrive.config.control import (  # noqa: F401  (NonNegativeProfile: re-export)
    ControlSettings,
    DriveSettings,
    NonNegativeProfile,
    OpenLoopSettings,
)
from imdrive.config.controller_model import ControllerModelSettings
from imdrive.config.deprecated_keys import drop_deprecated
from imdrive.config.estimators import (
    ESTIMATOR_SETTINGS,
    AfoSettings,
    EkfSettings,
    EstimatorSettings,
    FluxInjectionSettings,
    MrasSettings,
    ReactiveMrasSettings,
    package_sections,
)
from imdrive.config.inverter import InverterParams
from imdrive.config.machine import (  # noqa: F401  (preset_table: re-export)
    MachineParams,
    check_leakage_factor,
    machine_preset,
    machine_table,
    preset_table,
    resolve_machine_file,
)
from imdrive.config.output import OutputSettings

# the override walk, re-exported: importing it from imdrive.config.scenario keeps working
from imdrive.config.overrides import (  # noqa: F401  (the private ones: re-exports)
    FILE_PATHS,
    Key,
    _check_override_list,
    _convert,
    _fields,
    _schema_allows,
    _to_plain,
    apply_override,
    is_setting,
    is_table_class,
    override_items,
    parse_override,
    parse_toml,
    scenario_keys,
    scenario_root,
    set_path,
    setting_paths,
    table_paths,
)
from imdrive.config.pairs import apply_overrides, check_pairs, set_layer
from imdrive.config.plant import (  # noqa: F401  (C and the profile types: re-exports)
    C,
    LoadSettings,
    PlantSettings,
    PositiveProfile,
    SaturationSettings,
    ThermalSettings,
)
from imdrive.config.plugins import (
    HOW_TO_ALLOW,
    PluginSettings,
    allowing_plugins,
    import_plugins,
    resolve_plugin_paths,
)
from imdrive.config.profiles import Profile  # noqa: F401  (re-export)
from imdrive.config.r2_kalman import KalmanLawSettings  # noqa: F401  (the law registers)
from imdrive.config.r2_laws import law_sections
from imdrive.config.sensors import SensorSettings
from imdrive.config.simulation import DEFAULT_LOG_RATE_HZ, SimulationSettings, default_log_every
from imdrive.config.summary_file import summary_scenario
from imdrive.config.validation import (  # noqa: F401  (re-exports)
    Bool,
    Float,
    Int,
    Name,
    ProfileValues,
    Str,
    setting,
    settings,
    validate,
)
from imdrive.errors import ConfigError

__all__ = [
    "DEFAULT_LOG_RATE_HZ",
    "DEFAULT_MACHINE_PRESET",
    "FILE_PATHS",
    "SECTIONS",
    "AfoSettings",
    "CompensatorSettings",
    "ControlSettings",
    "ControllerModelSettings",
    "DriveSettings",
    "EkfSettings",
    "EstimatorSettings",
    "FluxInjectionSettings",
    "InjectionSettings",
    "Key",
    "LoadSettings",
    "MrasSettings",
    "OpenLoopSettings",
    "OutputSettings",
    "PlantSettings",
    "ReactiveMrasSettings",
    "SaturationSettings",
    "Scenario",
    "SensorSettings",
    "SimulationSettings",
    "ThermalSettings",
    "apply_override",
    "default_log_every",
    "is_setting",
    "is_table_class",
    "parse_override",
    "scenario_keys",
    "set_path",
    "setting_paths",
    "table_paths",
]


SECTIONS: dict[str, type] = {
    "plant": PlantSettings,
    "load": LoadSettings,
    "inverter": InverterParams,
    "drive": DriveSettings,
    "open_loop": OpenLoopSettings,
    "control": ControlSettings,
    "estimator": EstimatorSettings,
    "controller_model": ControllerModelSettings,
    **package_sections(),
    **law_sections(),
    "plugins": PluginSettings,
    "flux_injection": FluxInjectionSettings,
    "compensator": CompensatorSettings,
    "injection": InjectionSettings,
    "sensor": SensorSettings,
    "simulation": SimulationSettings,
    "output": OutputSettings,
}

DEFAULT_MACHINE_PRESET = "paper-table-iv"


@scenario_root
@settings("")
class Scenario:
    """A complete run: machine, inverter, drive, profiles, simulation settings, outputs.

    Built from a TOML-shaped dictionary by :meth:`from_dict` (the ``[machine]`` table holds
    ``preset`` and the fields that override it), or directly from the section objects.
    Every key, its unit and its default: ``docs/scenarios.md``.

    Attributes
    ----------
    name, description : str
        Name of the run (the default output folder is ``out/NAME``) and free text.
    machine : MachineParams
        The plant's machine.
    machine_preset : str
        The published parameter set the machine starts from (``machine.preset`` in a file).
    plant, load, inverter, drive, open_loop, control : settings section
        Time-varying plant, load torque, DC-link inverter, which controller drives it,
        open-loop voltage, field-oriented speed control.
    estimator, mras, reactive_mras, afo, ekf : settings section
        The controller's machine model, the speed estimators' and the R2 laws' settings (one
        section per estimator and per law of the package, from its settings class).
    controller_model : ControllerModelSettings
        The controller's magnetising curve and inverter-error table (commissioning's).
    plugins : PluginSettings
        Estimators from the user's own modules (``[plugins] modules``) and their settings
        (``[plugins.settings.NAME]``).
    flux_injection, compensator, injection : settings section
        Sinusoid on the flux command, the fuzzy R2 compensator, persistent excitation.
    sensor, simulation, output : settings section
        Current-sensor imperfections, integration and logging, the files ``imdrive run``
        writes.
    """

    name: Annotated[
        Name,
        setting(
            "name of the run; the default output folder is out/NAME, so 1-100 characters "
            "from A-Z a-z 0-9 . _ + -, starting with a letter or digit"
        ),
    ] = "scenario"
    description: Annotated[Str, setting("free text")] = ""
    machine: Annotated[MachineParams, setting("the plant's machine")] = machine_preset(
        DEFAULT_MACHINE_PRESET
    )
    machine_preset: Annotated[
        Str,
        setting(
            "the published parameter set the machine starts from (in a file: machine.preset); "
            "the other [machine] keys override its values"
        ),
    ] = DEFAULT_MACHINE_PRESET
    plant: Annotated[PlantSettings, setting("time-varying plant")] = PlantSettings()
    load: Annotated[LoadSettings, setting("load torque")] = LoadSettings()
    inverter: Annotated[InverterParams, setting("DC-link inverter")] = InverterParams()
    drive: Annotated[DriveSettings, setting("which controller drives the inverter")] = (
        DriveSettings()
    )
    open_loop: Annotated[OpenLoopSettings, setting("open-loop sinusoidal voltage")] = (
        OpenLoopSettings()
    )
    control: Annotated[ControlSettings, setting("field-oriented speed control")] = ControlSettings()
    estimator: Annotated[EstimatorSettings, setting("the controller's machine model")] = (
        EstimatorSettings()
    )
    controller_model: Annotated[
        ControllerModelSettings, setting("the controller's magnetising curve and inverter error")
    ] = ControllerModelSettings()
    # one section per estimator of the package (mras, reactive_mras, afo, ekf, ...) and per R2
    # law with a section (config/estimators.py, r2_laws.py): a new one adds its own
    for _section, _cls in (package_sections() | law_sections()).items():
        _doc = getattr(_cls, "estimator_description", None) or _cls.law_description
        __annotations__[_section] = Annotated[_cls, setting(_doc)]
        locals()[_section] = _cls()
    del _section, _cls
    plugins: Annotated[PluginSettings, setting("estimators from the user's own modules")] = (
        PluginSettings()
    )
    flux_injection: Annotated[FluxInjectionSettings, setting("sinusoid on the flux command")] = (
        FluxInjectionSettings()
    )
    compensator: Annotated[
        CompensatorSettings, setting("the fuzzy rotor-resistance compensator")
    ] = CompensatorSettings()
    injection: Annotated[InjectionSettings, setting("persistent excitation")] = InjectionSettings()
    sensor: Annotated[SensorSettings, setting("current-sensor imperfections")] = SensorSettings()
    simulation: Annotated[SimulationSettings, setting("integration and logging")] = (
        SimulationSettings()
    )
    output: Annotated[OutputSettings, setting("files imdrive run writes")] = OutputSettings()

    @model_validator(mode="before")
    @classmethod
    def _machine_table(cls, data):
        """The file form: ``[machine]`` is a preset name plus the fields that override it;
        the modules of ``[plugins]`` are imported first (their estimators register)."""
        if not isinstance(data, dict):
            return data  # direct construction: the objects themselves
        plugins = data.get("plugins")
        if isinstance(plugins, dict) and isinstance(plugins.get("modules"), list | tuple):
            import_plugins(plugins["modules"])
        elif isinstance(plugins, PluginSettings):
            import_plugins(plugins.modules)
        if "machine_preset" in data:
            raise ConfigError("machine_preset", "unknown key")
        if "machine" not in data or isinstance(data["machine"], MachineParams):
            return data
        table = data["machine"]
        if not isinstance(table, dict):
            raise ConfigError("machine", "must be a table")
        table = dict(table)
        preset = table.pop("preset", DEFAULT_MACHINE_PRESET)
        if not isinstance(preset, str):
            raise ConfigError("machine.preset", f"must be a string, got {preset!r}")
        data = dict(data)
        data["machine"] = machine_table(preset, table)  # preset < its file < this table
        data["machine_preset"] = preset
        return data

    @model_validator(mode="after")
    def _joint_rules(self):
        """Rules between sections, checked on the final scenario.

        Their arithmetic is on values each in range, but a quotient or product of extreme
        ones may still overflow: that is bad input (a :class:`ConfigError`), not a crash.
        """
        try:
            return self._rules_between_sections()
        except (ArithmeticError, ValueError) as exc:
            if isinstance(exc, ConfigError):
                raise
            raise ConfigError(
                "scenario",
                f"the rules between its sections cannot be evaluated ({type(exc).__name__}: "
                f"{exc}): some values are far outside a physical range",
            ) from None

    def _rules_between_sections(self):
        self._machine_defaults()
        resolve_ideal(self)  # controller_model.ideal: its tables from this plant
        check_pairs(self)  # before the per-unit values are resolved
        est, m = self.estimator, self.machine
        if (est.Ll1_H, est.Ll2_H, est.M_H) != (None, None, None):  # the controller's model
            given = [k for k in ("M_H", "Ll1_H", "Ll2_H") if getattr(est, k) is not None]
            check_leakage_factor(
                est.Ll1_H if est.Ll1_H is not None else m.Ll1_H,
                est.Ll2_H if est.Ll2_H is not None else m.Ll2_H,
                est.M_H if est.M_H is not None else m.M_H,
                f"estimator.{given[0]}",
            )
        inv = self.inverter
        if inv.model == "switching":
            f_Ts = inv.switching_frequency_Hz * self.simulation.Ts_s
            if abs(f_Ts - 1.0) > 1e-9:
                raise ConfigError(
                    "simulation.Ts_s",
                    f"must be 1/inverter.switching_frequency_Hz = "
                    f"{1.0 / inv.switching_frequency_Hz:g} s with the switching model (one "
                    f"carrier period per control period; got {self.simulation.Ts_s:g})",
                )
        fb = self.control.speed_feedback
        # an estimator that gives no flux error e_dq0 (AFO, EKF) gets the detection's own
        # (kernels/flux_detector.py): the compensator and the injection run with any estimator
        r2a = self.estimator.R2_adaptation
        if r2a != "compensator":
            if fb != r2a:
                raise ConfigError(
                    "estimator.R2_adaptation",
                    f'"{r2a}" needs control.speed_feedback = "{r2a}" (got "{fb}")',
                )
        t_dc = self.control.dead_time_compensation_s
        if t_dc is not None and not t_dc < 0.5 / inv.switching_frequency_Hz:
            raise ConfigError(
                "control.dead_time_compensation_s",
                "must be < half a switching period, 0.5/inverter.switching_frequency_Hz",
            )
        self._compensator_rules()
        plugin_rules(self)  # [plugins] checked and completed
        return self

    def estimator_settings(self):
        """The settings object of the estimator ``control.speed_feedback`` selects.

        Returns
        -------
        object
            Its section (``self.mras`` for the MRAS and for "measured"), or for a plug-in
            estimator its ``[plugins.settings.NAME]`` table validated by its settings class
            (defaults where the table is absent).
        """
        name = self.control.speed_feedback
        if name != "measured" and name not in ESTIMATOR_SETTINGS:
            raise ConfigError(
                "control.speed_feedback",
                f'"{name}" is a plug-in estimator whose module was not imported '
                f"(plugins.modules: {list(self.plugins.modules)}; {HOW_TO_ALLOW})",
            )
        cls = ESTIMATOR_SETTINGS["mras" if name == "measured" else name]
        if cls.estimator_section is not None:
            return getattr(self, cls.estimator_section)
        return validate(cls, self.plugins.settings.get(name, {}), f"plugins.settings.{name}")

    def _machine_defaults(self) -> None:
        """The defaults that follow the machine (:func:`imdrive.config.checks.machine_defaults`)."""
        machine_defaults(self)

    def _compensator_rules(self) -> None:
        """The compensator against the run (:func:`imdrive.config.checks.compensator_rules`)."""
        compensator_rules(self)

    def _per_unit_warnings(self, r) -> None:
        """Absolute values far from the machine (:func:`.checks.per_unit_warnings`)."""
        per_unit_warnings(self, r)

    # -- construction ----------------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: dict, *, allow_plugins: bool | None = None) -> Scenario:
        """Build and validate a scenario from its TOML-shaped dictionary.

        Parameters
        ----------
        data : dict
            The scenario file's tables, as ``tomllib`` reads them.
        allow_plugins : bool, optional
            True: import the modules of ``[plugins] modules`` (their code runs); default: only
            with ``IMDRIVE_ALLOW_PLUGINS=1`` (:mod:`imdrive.config.plugins`), else a module not
            yet imported is refused.

        Returns
        -------
        Scenario
            The validated scenario.
        """
        if not isinstance(data, dict):
            raise ConfigError("scenario", "must be a table")
        data = drop_deprecated(data)  # keys of earlier releases: a warning, no effect
        with allowing_plugins(allow_plugins):
            scenario = validate(cls, data)
        drive_mode_given(data)  # after each section's rules: [control] without [drive]
        return scenario

    @classmethod
    def from_toml(cls, text: str, overrides=(), *, base_dir=None, allow_plugins=None) -> Scenario:
        """Parse TOML text, apply ``key.path=value`` overrides, validate.

        Parameters
        ----------
        text : str
            A scenario file's text.
        overrides : list of str
            ``key.path=value`` strings (values parsed as TOML), applied in order.
        base_dir : str or pathlib.Path, optional
            The folder a relative ``[machine] file`` or ``[plugins] modules`` path of ``text``
            is read from (the scenario file's); default the working directory, as for an
            override's.
        allow_plugins : bool, optional
            Import the scenario's plug-in modules (:meth:`from_dict`).

        Returns
        -------
        Scenario
            The validated scenario.
        """
        _check_override_list(overrides)
        if not isinstance(text, str):
            raise ConfigError("text", f"must be the TOML text (a str), got {type(text).__name__}")
        if base_dir is not None and not isinstance(base_dir, str | PathLike):
            raise ConfigError("base_dir", f"must be a folder path, got {type(base_dir).__name__}")
        data = parse_toml(text, "scenario")
        resolve_machine_file(data, base_dir)
        resolve_plugin_paths(data, base_dir)
        apply_overrides(data, overrides)  # one layer on the file (config/pairs.py)
        return cls.from_dict(data, allow_plugins=allow_plugins)

    @classmethod
    def read(
        cls,
        preset_or_path: str,
        overrides: list[str] | tuple[str, ...] = (),
        *,
        allow_plugins: bool | None = None,
    ) -> Scenario:
        """A built-in preset by name, or a scenario file by path.

        Parameters
        ----------
        preset_or_path : str or pathlib.Path
            A preset name (``imdrive presets``), a TOML scenario file, or a run's
            ``summary.json`` (its ``"scenario"``, to run it again).
        overrides : list of str
            ``key.path=value`` strings (values parsed as TOML), as ``imdrive run --set``.
        allow_plugins : bool, optional
            Import its plug-in modules, relative paths from the file's folder (:meth:`from_dict`).

        Returns
        -------
        Scenario
            The validated scenario.
        """
        import os

        from imdrive.config.presets import preset_names, scenario_text

        if isinstance(preset_or_path, os.PathLike):
            preset_or_path = os.fspath(preset_or_path)
        if not isinstance(preset_or_path, str) or not preset_or_path:
            raise ConfigError(
                "preset_or_path",
                "must be a preset name or a file path (a non-empty str or os.PathLike), got "
                f"{type(preset_or_path).__name__}",
            )
        _check_override_list(overrides)
        if str(preset_or_path).endswith(".json") and preset_or_path not in preset_names():
            data = summary_scenario(preset_or_path)  # a run's summary.json: its scenario
            apply_overrides(data, overrides)
            return cls.from_dict(data, allow_plugins=allow_plugins)
        base_dir = None if preset_or_path in preset_names() else Path(preset_or_path).parent
        text = scenario_text(preset_or_path, FILE_KEYS)
        return cls.from_toml(text, overrides, base_dir=base_dir, allow_plugins=allow_plugins)

    def with_(self, **changes) -> Scenario:
        """A copy with whole sections replaced (``sc.with_(simulation=...)``), validated again.

        Parameters
        ----------
        **changes
            Field name -> new section object (or value for ``name``, ``description``).

        Returns
        -------
        Scenario
            The new, validated scenario.
        """
        return replace(self, **changes)

    def with_overrides(self, overrides) -> Scenario:
        """A new, validated scenario with dotted-key overrides applied.

        Parameters
        ----------
        overrides : list of str or dict
            ``["control.speed_ref_rpm=1500", "estimator.R2_ohm=0.9"]`` (values parsed as TOML,
            as ``--set`` does) or ``{"control.speed_ref_rpm": 1500, ...}``.

        Returns
        -------
        Scenario
            The new scenario; ``self`` is unchanged.

        Raises
        ------
        ConfigError
            Naming the key for an unknown setting or a value that breaks a rule.
        """
        items = override_items(overrides)
        data = self.to_dict()
        if getattr(self.simulation, "_log_every_auto", False):
            # the default decimation follows Ts_s: let it be derived again from the new one
            data["simulation"].pop("log_every", None)
        if any(parts[:2] in (("machine", "preset"), ("machine", "file")) for parts, _ in items):
            # another parameter set: keep only what this scenario changed of its own
            base = preset_table(self.machine_preset)
            data["machine"] = {
                k: v
                for k, v in data["machine"].items()
                if k == "preset" or k not in base or base[k] != v
            }
        set_layer(data, items, "the overrides")  # a pair's other member is cleared
        return Scenario.from_dict(data)

    # -- export ----------------------------------------------------------------------------
    def to_toml(self) -> str:
        """The scenario as TOML text, every default filled in (``imdrive show PRESET --all``);
        an unset setting whose default depends on the scenario says what it is here.

        Returns
        -------
        str
            TOML text that :meth:`from_toml` reads back to an equal scenario.
        """
        from imdrive.config.resolved import resolved_defaults
        from imdrive.config.toml_writer import dumps

        return dumps(self.to_dict(), resolved_defaults(self))

    def to_dict(self) -> dict:
        """The scenario as run, every default filled in, in TOML-shaped form.

        Returns
        -------
        dict
            Section name -> table, in the units of the scenario file.
        """
        out: dict = {"name": self.name, "description": self.description}
        m = {"preset": self.machine_preset}
        m.update({k: v for k, v in self.machine.to_dict().items() if k != "description"})
        out["machine"] = m
        for key in SECTIONS:
            out[key] = _to_plain(getattr(self, key))
        if getattr(self.inverter, "_Vdc_V_auto", False):  # derived from the machine: unset
            out["inverter"]["Vdc_V"] = None
        if getattr(self.simulation, "_t_end_s_auto", False):  # from tracking_windows: unset
            del out["simulation"]["t_end_s"]
        return out


# the estimators' and laws' sections come from their settings classes, so a new one of the
# package is named in the docstring without an edit here
_FOUR = "mras, reactive_mras, afo, ekf"
assert Scenario.__doc__ and _FOUR in Scenario.__doc__
Scenario.__doc__ = Scenario.__doc__.replace(_FOUR, ", ".join(package_sections() | law_sections()))
del _FOUR
#: a scenario file's top-level keys (a file with none of them is refused unread, presets.py)
FILE_KEYS = frozenset(f.name for f in fields(Scenario)) - {"machine_preset"}
