"""Scenarios: a whole run described by frozen dataclasses, read from and written to TOML.

A scenario file has these tables (every key optional unless said otherwise; ``imdrive show
PRESET`` prints complete examples)::

    name, description            strings
    [machine]      preset = "paper-table-iv" | "krause-3hp", and any MachineParams field
    [plant]        R1_scale, R2_scale (profiles), speed_mode = "dynamic" | "imposed",
                   imposed_speed_rpm (profile)
    [plant.thermal] enabled, alpha1_per_K, alpha2_per_K, theta_ref_C, theta_amb_C, theta_init_C,
                   Rth1_K_per_W, tau1_s, Rth2_K_per_W, tau2_s
    [load]         torque_Nm (profile), viscous_Nms, fan_Nms2
    [inverter]     Vdc_V, model = "average"
    [drive]        mode = "open-loop" | "vector"
    [open_loop]    voltage_V (line-to-line rms, profile), frequency_Hz (profile), vf_ramp_s
    [control]      speed_feedback = "measured" | "mras", speed_ref_rpm (profile),
                   flux_ref_Wb (profile; default rated flux), speed_bandwidth_Hz,
                   current_bandwidth_Hz, speed_kp, speed_ki, current_kp, current_ki,
                   current_limit_A, decoupling
    [estimator]    the controller's machine model: R1_ohm, R2_ohm (initial R2_hat), Ll1_H,
                   Ll2_H, M_H (each defaults to the plant's value)
    [mras]         wc_rad_s, bandwidth_Hz, K1, K2
    [compensator]  enabled, t_on_s, period_s, gain_E_per_Wb, gain_DE_per_Wb, G_CR_ohm,
                   R2_min_ohm, R2_max_ohm, table = "paper" | "rules",
                   input = "e_d0" | "demodulated", average
    [injection]    amplitude_A, frequency_Hz, t_on_s, lowpass_rad_s (sinusoid added to id*)
    [sensor]       i_offset_alpha_A, i_offset_beta_A
    [simulation]   t_end_s, Ts_s, substeps, log_every, divergence_current_A, divergence_speed_rpm
    [output]       figures, csv

Profiles are written as in :mod:`imdrive.profiles`. Unknown keys, wrong types and values that
break a rule raise :class:`~imdrive.errors.ConfigError` naming the field.
"""

from __future__ import annotations

import math
import tomllib
import types
import typing
from dataclasses import dataclass, field, fields, is_dataclass, replace

from imdrive.config.inverter import InverterParams
from imdrive.config.machine import MachineParams, machine_preset
from imdrive.config.profiles import Profile, parse_profile
from imdrive.errors import ConfigError


def _check(cond: bool, path: str, rule: str) -> None:
    if not cond:
        raise ConfigError(path, rule)


def _pos(value: float, path: str) -> None:
    _check(math.isfinite(value) and value > 0, path, f"must be > 0 (got {value})")


def _nonneg(value: float, path: str) -> None:
    _check(math.isfinite(value) and value >= 0, path, f"must be >= 0 (got {value})")


def _choice(value: str, choices: tuple[str, ...], path: str) -> None:
    _check(value in choices, path, f"must be one of {', '.join(repr(c) for c in choices)}")


C = Profile.constant


@dataclass(frozen=True)
class ThermalSettings:
    """First-order thermal model of each winding (section ``[plant.thermal]``)."""

    enabled: bool = False
    alpha1_per_K: float = 0.00393  # copper
    alpha2_per_K: float = 0.00393
    theta_ref_C: float = 20.0
    theta_amb_C: float = 20.0
    theta_init_C: float = 20.0
    Rth1_K_per_W: float = 0.4
    tau1_s: float = 1200.0
    Rth2_K_per_W: float = 0.4
    tau2_s: float = 1200.0

    def __post_init__(self):
        for n in ("Rth1_K_per_W", "tau1_s", "Rth2_K_per_W", "tau2_s"):
            _pos(getattr(self, n), f"plant.thermal.{n}")
        for n in ("alpha1_per_K", "alpha2_per_K"):
            _nonneg(getattr(self, n), f"plant.thermal.{n}")


@dataclass(frozen=True)
class PlantSettings:
    """Time-varying plant (section ``[plant]``): resistance changes, imposed speed."""

    R1_scale: Profile = field(default_factory=lambda: C(1.0))
    R2_scale: Profile = field(default_factory=lambda: C(1.0))
    speed_mode: str = "dynamic"
    imposed_speed_rpm: Profile = field(default_factory=lambda: C(0.0))
    thermal: ThermalSettings = field(default_factory=ThermalSettings)

    def __post_init__(self):
        _choice(self.speed_mode, ("dynamic", "imposed"), "plant.speed_mode")
        for n in ("R1_scale", "R2_scale"):
            _check(all(v > 0 for _, v in getattr(self, n).points), f"plant.{n}", "must be > 0")


@dataclass(frozen=True)
class LoadSettings:
    """Load torque ``T_L = torque_Nm(t) + viscous_Nms w_m + fan_Nms2 w_m |w_m|`` (``[load]``)."""

    torque_Nm: Profile = field(default_factory=lambda: C(0.0))
    viscous_Nms: float = 0.0
    fan_Nms2: float = 0.0


@dataclass(frozen=True)
class DriveSettings:
    """Which controller drives the inverter (``[drive]``)."""

    mode: str = "open-loop"

    def __post_init__(self):
        _choice(self.mode, ("open-loop", "vector"), "drive.mode")


@dataclass(frozen=True)
class OpenLoopSettings:
    """Balanced sinusoidal voltage (``[open_loop]``); voltage is line-to-line rms."""

    voltage_V: Profile = field(default_factory=lambda: C(220.0))
    frequency_Hz: Profile = field(default_factory=lambda: C(60.0))
    vf_ramp_s: float = 0.0

    def __post_init__(self):
        _nonneg(self.vf_ramp_s, "open_loop.vf_ramp_s")
        _check(all(v >= 0 for _, v in self.voltage_V.points), "open_loop.voltage_V", "must be >= 0")
        if self.vf_ramp_s > 0:
            _check(
                len(self.voltage_V.points) == 1 and len(self.frequency_Hz.points) == 1,
                "open_loop.vf_ramp_s",
                "needs constant voltage_V and frequency_Hz (the ramp ends at them)",
            )


@dataclass(frozen=True)
class ControlSettings:
    """Indirect field-oriented speed control (``[control]``)."""

    speed_feedback: str = "measured"
    speed_ref_rpm: Profile = field(default_factory=lambda: C(0.0))
    flux_ref_Wb: Profile | None = None
    speed_bandwidth_Hz: float = 5.0
    current_bandwidth_Hz: float = 200.0
    speed_kp: float | None = None
    speed_ki: float | None = None
    current_kp: float | None = None
    current_ki: float | None = None
    current_limit_A: float | None = None
    decoupling: bool = True

    def __post_init__(self):
        _choice(self.speed_feedback, ("measured", "mras"), "control.speed_feedback")
        _pos(self.speed_bandwidth_Hz, "control.speed_bandwidth_Hz")
        _pos(self.current_bandwidth_Hz, "control.current_bandwidth_Hz")
        for n in ("speed_kp", "speed_ki", "current_kp", "current_ki"):
            v = getattr(self, n)
            if v is not None:
                _check(math.isfinite(v), f"control.{n}", "must be finite")
        if self.current_limit_A is not None:
            _pos(self.current_limit_A, "control.current_limit_A")
        if self.flux_ref_Wb is not None:
            _check(
                all(v > 0 for _, v in self.flux_ref_Wb.points), "control.flux_ref_Wb", "must be > 0"
            )


@dataclass(frozen=True)
class EstimatorSettings:
    """The controller's and estimator's machine model (``[estimator]``); None = the plant's."""

    R1_ohm: float | None = None
    R2_ohm: float | None = None
    Ll1_H: float | None = None
    Ll2_H: float | None = None
    M_H: float | None = None

    def __post_init__(self):
        for f in fields(self):
            v = getattr(self, f.name)
            if v is not None:
                _pos(v, f"estimator.{f.name}")


@dataclass(frozen=True)
class MrasSettings:
    """Schauder's MRAS (``[mras]``). K1, K2 default from ``bandwidth_Hz`` (see mras module)."""

    wc_rad_s: float = 5.0
    bandwidth_Hz: float = 40.0
    K1: float | None = None
    K2: float | None = None

    def __post_init__(self):
        _nonneg(self.wc_rad_s, "mras.wc_rad_s")
        _pos(self.bandwidth_Hz, "mras.bandwidth_Hz")
        for n in ("K1", "K2"):
            v = getattr(self, n)
            if v is not None:
                _check(math.isfinite(v), f"mras.{n}", "must be finite")


@dataclass(frozen=True)
class CompensatorSettings:
    """The fuzzy rotor-resistance compensator (``[compensator]``, paper §4).

    ``gain_E_per_Wb`` and ``gain_DE_per_Wb`` scale e_d0 and its change per period before the
    quantiser (thresholds 0.25 ... 5): 1e6 reproduces the paper's micro-weber thresholds.
    ``G_CR_ohm`` is the change of R2_hat per output level and period. The clamps default to
    0.5 and 2 times the initial estimate. ``period_s`` defaults to 10 ms, or to one injection
    period with ``input = "demodulated"``.
    """

    enabled: bool = False
    t_on_s: float = 0.0
    period_s: float | None = None
    gain_E_per_Wb: float = 1e6
    gain_DE_per_Wb: float = 1e6
    G_CR_ohm: float = 0.001
    R2_min_ohm: float | None = None
    R2_max_ohm: float | None = None
    table: str = "paper"
    input: str = "e_d0"
    average: bool = True

    def __post_init__(self):
        _nonneg(self.t_on_s, "compensator.t_on_s")
        if self.period_s is not None:
            _pos(self.period_s, "compensator.period_s")
        _pos(self.gain_E_per_Wb, "compensator.gain_E_per_Wb")
        _pos(self.gain_DE_per_Wb, "compensator.gain_DE_per_Wb")
        _nonneg(self.G_CR_ohm, "compensator.G_CR_ohm")
        for n in ("R2_min_ohm", "R2_max_ohm"):
            if getattr(self, n) is not None:
                _pos(getattr(self, n), f"compensator.{n}")
        if self.R2_min_ohm is not None and self.R2_max_ohm is not None:
            _check(
                self.R2_min_ohm < self.R2_max_ohm,
                "compensator.R2_min_ohm",
                "must be < compensator.R2_max_ohm",
            )
        _choice(self.table, ("paper", "rules"), "compensator.table")
        _choice(self.input, ("e_d0", "demodulated"), "compensator.input")


@dataclass(frozen=True)
class InjectionSettings:
    """Persistent excitation (``[injection]``): a sinusoid added to the flux-current reference.

    ``amplitude_A`` = 0 switches it off. The compensator's ``input = "demodulated"`` feeds on
    e_d0 detected synchronously with this sinusoid; its period should be a whole number of
    injection periods (the default compensator period for that input is one).
    """

    amplitude_A: float = 0.0
    frequency_Hz: float = 2.0
    t_on_s: float = 0.0
    lowpass_rad_s: float = 0.0

    def __post_init__(self):
        _nonneg(self.amplitude_A, "injection.amplitude_A")
        _nonneg(self.t_on_s, "injection.t_on_s")
        _pos(self.frequency_Hz, "injection.frequency_Hz")
        _nonneg(self.lowpass_rad_s, "injection.lowpass_rad_s")


@dataclass(frozen=True)
class SensorSettings:
    """Current-sensor imperfections (``[sensor]``)."""

    i_offset_alpha_A: float = 0.0
    i_offset_beta_A: float = 0.0


@dataclass(frozen=True)
class SimulationSettings:
    """Integration and logging (``[simulation]``)."""

    t_end_s: float = 1.0
    Ts_s: float = 100e-6
    substeps: int = 1
    log_every: int = 1
    divergence_current_A: float | None = None
    divergence_speed_rpm: float = 20000.0

    def __post_init__(self):
        _pos(self.t_end_s, "simulation.t_end_s")
        _pos(self.Ts_s, "simulation.Ts_s")
        _check(self.Ts_s <= self.t_end_s, "simulation.Ts_s", "must be <= simulation.t_end_s")
        _check(self.substeps >= 1, "simulation.substeps", f"must be >= 1 (got {self.substeps})")
        _check(self.log_every >= 1, "simulation.log_every", f"must be >= 1 (got {self.log_every})")
        _check(self.t_end_s / self.Ts_s <= 2e9, "simulation.Ts_s", "gives more than 2e9 periods")
        if self.divergence_current_A is not None:
            _pos(self.divergence_current_A, "simulation.divergence_current_A")
        _pos(self.divergence_speed_rpm, "simulation.divergence_speed_rpm")

    @property
    def n_steps(self) -> int:
        return int(round(self.t_end_s / self.Ts_s))


@dataclass(frozen=True)
class OutputSettings:
    """What ``imdrive run`` writes besides summary.json (``[output]``)."""

    figures: bool = True
    csv: bool = True


SECTIONS: dict[str, type] = {
    "plant": PlantSettings,
    "load": LoadSettings,
    "inverter": InverterParams,
    "drive": DriveSettings,
    "open_loop": OpenLoopSettings,
    "control": ControlSettings,
    "estimator": EstimatorSettings,
    "mras": MrasSettings,
    "compensator": CompensatorSettings,
    "injection": InjectionSettings,
    "sensor": SensorSettings,
    "simulation": SimulationSettings,
    "output": OutputSettings,
}


@dataclass(frozen=True)
class Scenario:
    """A complete run: machine, inverter, drive, profiles, simulation settings, outputs."""

    name: str = "scenario"
    description: str = ""
    machine: MachineParams = field(default_factory=machine_preset)
    machine_preset: str = "paper-table-iv"
    plant: PlantSettings = field(default_factory=PlantSettings)
    load: LoadSettings = field(default_factory=LoadSettings)
    inverter: InverterParams = field(default_factory=InverterParams)
    drive: DriveSettings = field(default_factory=DriveSettings)
    open_loop: OpenLoopSettings = field(default_factory=OpenLoopSettings)
    control: ControlSettings = field(default_factory=ControlSettings)
    estimator: EstimatorSettings = field(default_factory=EstimatorSettings)
    mras: MrasSettings = field(default_factory=MrasSettings)
    compensator: CompensatorSettings = field(default_factory=CompensatorSettings)
    injection: InjectionSettings = field(default_factory=InjectionSettings)
    sensor: SensorSettings = field(default_factory=SensorSettings)
    simulation: SimulationSettings = field(default_factory=SimulationSettings)
    output: OutputSettings = field(default_factory=OutputSettings)

    # -- construction ----------------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: dict) -> Scenario:
        """Build and validate a scenario from its TOML-shaped dictionary."""
        if not isinstance(data, dict):
            raise ConfigError("scenario", "must be a table")
        kw: dict = {}
        for key, val in data.items():
            if key in ("name", "description"):
                _check(isinstance(val, str), key, "must be a string")
                kw[key] = val
            elif key == "machine":
                kw["machine_preset"], kw["machine"] = _machine_from_dict(val)
            elif key in SECTIONS:
                kw[key] = _from_dict(SECTIONS[key], val, key)
            else:
                raise ConfigError(key, "unknown key")
        return cls(**kw)

    @classmethod
    def from_toml(cls, text: str, overrides: list[str] | tuple[str, ...] = ()) -> Scenario:
        """Parse TOML text, apply ``key.path=value`` overrides, validate."""
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError("scenario", f"invalid TOML: {exc}") from None
        from imdrive.config.overrides import apply_override

        for ov in overrides:
            apply_override(data, ov)
        return cls.from_dict(data)

    @classmethod
    def read(cls, preset_or_path: str, overrides: list[str] | tuple[str, ...] = ()) -> Scenario:
        """A built-in preset by name, or a scenario file by path."""
        from imdrive.config.presets import scenario_text

        return cls.from_toml(scenario_text(preset_or_path), overrides)

    def with_(self, **changes) -> Scenario:
        return replace(self, **changes)

    # -- export ----------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """The scenario as run, every default filled in, in TOML-shaped form."""
        out: dict = {"name": self.name, "description": self.description}
        m = {"preset": self.machine_preset}
        m.update({k: v for k, v in self.machine.to_dict().items() if k != "description"})
        out["machine"] = m
        for key in SECTIONS:
            out[key] = _to_plain(getattr(self, key))
        return out


def _to_plain(obj):
    if isinstance(obj, Profile):
        return obj.to_toml_value()
    if is_dataclass(obj):
        return {f.name: _to_plain(getattr(obj, f.name)) for f in fields(obj)}
    return obj


def _machine_from_dict(val) -> tuple[str, MachineParams]:
    if not isinstance(val, dict):
        raise ConfigError("machine", "must be a table")
    val = dict(val)
    preset = val.pop("preset", "paper-table-iv")
    _check(isinstance(preset, str), "machine.preset", "must be a string")
    hints = typing.get_type_hints(MachineParams)
    conv = {}
    for k, v in val.items():
        if k not in hints:
            raise ConfigError(f"machine.{k}", "unknown key")
        conv[k] = _convert(hints[k], v, f"machine.{k}")
    return preset, machine_preset(preset, **conv)


def _from_dict(cls, data, path: str):
    if not isinstance(data, dict):
        raise ConfigError(path, "must be a table")
    hints = typing.get_type_hints(cls)
    names = {f.name for f in fields(cls)}
    kw = {}
    for key, val in data.items():
        if key not in names:
            raise ConfigError(f"{path}.{key}", "unknown key")
        kw[key] = _convert(hints[key], val, f"{path}.{key}")
    return cls(**kw)


def _type_name(tp) -> str:
    return getattr(tp, "__name__", str(tp))


def _convert(tp, val, path: str):
    """Check ``val`` against the annotation ``tp`` and convert it."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if val is None:
            return None
        return _convert(args[0], val, path)
    if tp is Profile:
        return parse_profile(path, val)
    if is_dataclass(tp):
        return _from_dict(tp, val, path)
    if tp is bool:
        _check(isinstance(val, bool), path, f"must be true or false, got {val!r}")
        return val
    if tp is int:
        ok = isinstance(val, int) and not isinstance(val, bool)
        ok = ok or (isinstance(val, float) and val.is_integer())
        _check(ok, path, f"must be an integer, got {val!r}")
        return int(val)
    if tp is float:
        ok = isinstance(val, int | float) and not isinstance(val, bool)
        _check(ok, path, f"must be a number, got {val!r}")
        _check(math.isfinite(val), path, "must be finite")
        return float(val)
    if tp is str:
        _check(isinstance(val, str), path, f"must be a string, got {val!r}")
        return val
    raise TypeError(f"unsupported annotation {_type_name(tp)} at {path}")  # programming error
