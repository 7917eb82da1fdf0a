"""Settings given either as an absolute value or in per-unit of the machine: the pairs, and
how an override of one member treats the other.

Several settings exist twice, an absolute key and its per-unit twin (``estimator.R2_ohm`` and
``estimator.R2_ratio``, ``mras.R1_rate_per_s`` and ``mras.R1_rate_pu``, ...): both say the same
thing, and the per-unit one follows the machine (:mod:`imdrive.config.perunit` turns it into
the SI value). :data:`PAIRS` declares every such pair once.

A scenario is built in layers: a preset or scenario file, then the overrides on top of it
(``imdrive run --set``, a sweep's ``[set]`` table on its ``base``, a sweep axis,
:meth:`~imdrive.config.scenario.Scenario.with_overrides`). When an override sets one member
of a pair while the layer underneath carries the other, the other is cleared (it takes its
default) and a :class:`~imdrive.errors.ConfigWarning` says which key replaced which
(:func:`set_layer`): ``--set mras.R1_rate_per_s=0.5`` on a preset that states
``mras.R1_rate_pu`` runs at 0.5 /s. Both members set in one layer (one file, one list of
overrides) are refused with a :class:`~imdrive.errors.ConfigError` naming both
(:func:`check_pairs`); for the pairs whose per-unit member was documented to replace the
absolute one, that still works, with a warning that it is deprecated.
"""

from __future__ import annotations

import dataclasses
import functools
import warnings
from dataclasses import dataclass
from typing import Literal

from imdrive.config.overrides import dotted, parse_override, scenario_keys, set_path
from imdrive.config.profiles import Profile, parse_profile
from imdrive.errors import ConfigError, ConfigWarning

__all__ = ["PAIRS", "Pair", "apply_overrides", "check_pairs", "pair_of", "set_layer"]


@dataclass(frozen=True)
class Pair:
    """One setting stated as an absolute value or in per-unit of the machine.

    Attributes
    ----------
    absolute : tuple of str
        The absolute key(s), dotted (``("estimator.R2_ohm",)``). A group of keys (the injection
        frequencies) is one setting: an override of any member clears every member of the
        other group.
    per_unit : tuple of str
        The per-unit twin(s), in the same order.
    base : str
        What the per-unit value multiplies (for the docs).
    both : {"error", "per_unit", "absolute"}
        Both set in one layer: ``"error"`` refuses it; ``"per_unit"`` / ``"absolute"`` names
        the member the run then uses, as documented before the pairs were declared
        (deprecated: a warning says so).
    quiet : bool
        An override of one member clears the other without a warning: a profile, which an
        override restates whole (the speed reference, the load).
    machine_bound : bool
        The absolute member is a value of the machine it was stated for, named when the
        machine is replaced under it (:func:`_warn_machine_replaced`); false for a run's
        length, which suits any machine as the duty cycle it states.
    """

    absolute: tuple[str, ...]
    per_unit: tuple[str, ...]
    base: str
    both: Literal["error", "per_unit", "absolute"] = "error"
    quiet: bool = False
    machine_bound: bool = True

    @property
    def keys(self) -> tuple[str, ...]:
        return self.absolute + self.per_unit

    def twins(self, key: str) -> tuple[str, ...]:
        """The keys an override of ``key`` clears (the other group)."""
        return self.per_unit if key in self.absolute else self.absolute


def _pair(
    absolute: str, per_unit: str, base: str, both: str = "error", quiet=False, bound=True
) -> Pair:
    return Pair((absolute,), (per_unit,), base, both, quiet, bound)


#: Every absolute / per-unit pair of the scenario file.
PAIRS: tuple[Pair, ...] = (
    _pair("control.speed_ref_rpm", "control.speed_ref_pu", "the machine's rated speed", quiet=True),
    _pair("load.torque_Nm", "load.torque_pu", "the machine's rated torque", quiet=True),
    _pair(
        "simulation.t_end_s",
        "simulation.tracking_windows",
        "R2 tracking's decision window, from compensator.t_on_s",
        quiet=True,
        bound=False,
    ),
    _pair("estimator.R1_ohm", "estimator.R1_ratio", "the plant's R1"),
    _pair("estimator.R2_ohm", "estimator.R2_ratio", "the plant's R2"),
    _pair("estimator.M_H", "estimator.M_ratio", "the plant's M"),
    _pair("compensator.R2_min_ohm", "compensator.R2_min_ratio", "the initial R̂2"),
    _pair("compensator.R2_max_ohm", "compensator.R2_max_ratio", "the initial R̂2"),
    _pair("compensator.G_CR_ohm", "compensator.G_CR_pu", "the initial R̂2", "per_unit"),
    _pair("compensator.gain_E_per_Wb", "compensator.gain_E_pu", "1/ψ_rated", "per_unit"),
    _pair(
        "compensator.gate_band_Hz",
        "compensator.gate_band_pu",
        "the first injection frequency",
        "per_unit",
    ),
    _pair(
        "compensator.gate_speed_rpm",
        "compensator.gate_speed_pu",
        "the rated slip speed",
        "per_unit",
    ),
    _pair("compensator.gate_iq_A", "compensator.gate_iq_pu", "the rated current", "per_unit"),
    _pair("injection.amplitude_A", "injection.amplitude_pu", "ψ_rated / M", "per_unit"),
    _pair(
        "injection.frequency_Hz",
        "injection.frequency_pu",
        "the rotor corner R̂2/(2π L̂2)",
        "per_unit",
    ),
    _pair("mras.R1_rate_per_s", "mras.R1_rate_pu", "the rotor corner R2/L2"),
    _pair("mras.R1_max_freq_Hz", "mras.R1_max_freq_pu", "the rated frequency"),
    _pair("sensor.adc_range_A", "sensor.adc_range_pu", "the rated peak current"),
    _pair("inverter.sign_band_A", "inverter.sign_band_pu", "the rated peak current"),
    _pair("ekf.voltage_noise_V", "ekf.voltage_noise_pu", "the rated phase voltage's peak"),
    _pair("ekf.flux_noise_Wb_per_s", "ekf.flux_noise_pu", "ψ_rated / T2"),
    _pair(
        "ekf.acceleration_noise_rad_s2",
        "ekf.acceleration_noise_pu",
        "the rated acceleration n_p T_rated / J",
    ),
    _pair("ekf.R2_drift_ohm_per_s", "ekf.R2_drift_pu", "the plant's R2 / T2"),
    _pair("ekf.current_noise_A", "ekf.current_noise_pu", "the rated peak current"),
    _pair("plant.thermal.Rth1_K_per_W", "plant.thermal.Rth1_pu", "80 K / the rated stator losses"),
    _pair("plant.thermal.Rth2_K_per_W", "plant.thermal.Rth2_pu", "80 K / the rated rotor losses"),
    _pair("afo.R1_bandwidth_rad_s", "afo.R1_bandwidth_pu", "the rotor corner R2/L2"),
    _pair("afo.R2_bandwidth_rad_s", "afo.R2_bandwidth_pu", "the rotor corner R2/L2"),
    _pair(
        "flux_injection.frequency_Hz",
        "flux_injection.frequency_pu",
        "the rotor corner R̂2/(2π L̂2)",
    ),
    _pair(
        "smo_mras.switching_gain_rad_s",
        "smo_mras.speed_error_pu",
        "2π × the rated frequency",
        "absolute",
    ),
)


@functools.cache
def _by_key() -> dict[str, Pair]:
    return {k: p for p in PAIRS for k in p.keys}


def pair_of(key: str) -> Pair | None:
    """The pair dotted ``key`` belongs to, or None."""
    return _by_key().get(key)


@functools.cache
def _default(key: str):
    k = next(k for k in scenario_keys() if k.dotted == key)
    return None if k.default is dataclasses.MISSING else k.default


def _is_set(key: str, value) -> bool:
    """Whether ``value`` states ``key``: given and not its default (an absolute key whose
    default is a number, ``mras.R1_rate_per_s = 0``, is unset at that number)."""
    default = _default(key)
    if value is not None and isinstance(default, Profile) and not isinstance(value, Profile):
        try:  # a profile as the file writes it (0, a table): compared as a profile
            value = parse_profile(key, value)
        except ConfigError:
            return True
    return value is not None and value != default


def _section(data: dict, key: str) -> tuple[dict | None, str]:
    *head, name = key.split(".")
    node = data
    for p in head:
        node = node.get(p) if isinstance(node, dict) else None
    return (node if isinstance(node, dict) else None), name


def _check_layer(items: list[tuple[str, object]], where: str) -> None:
    """Both members of a pair stated in one layer of overrides: refused (or, for a pair whose
    ``both`` names a member, warned and left to :func:`check_pairs`)."""
    given = {k for k, v in items if pair_of(k) is not None and v is not None}
    for p in PAIRS:
        a = [k for k in p.absolute if k in given and _is_set(k, dict(items)[k])]
        u = [k for k in p.per_unit if k in given and _is_set(k, dict(items)[k])]
        if a and u and p.both == "error":
            raise ConfigError(u[0], f"set {a[0]} or {u[0]}, not both (both in {where})")


def set_layer(data: dict, items, where: str = "the overrides") -> None:
    """Set one layer of overrides on a TOML-shaped scenario dictionary.

    Each ``(path, value)`` goes through :func:`~imdrive.config.overrides.set_path`; a member of
    a pair (:data:`PAIRS`) set to a value clears the other member(s) from ``data`` unless this
    layer sets them too, with a :class:`ConfigWarning` naming both when the cleared one was
    stated.

    Parameters
    ----------
    data : dict
        The scenario's tables (changed in place).
    items : iterable of (tuple, object)
        Paths (as :func:`~imdrive.config.overrides.parse_override` returns them) and values.
    where : str
        What the layer is, for the message (``"--set"``, ``"[set]"``).

    Raises
    ------
    ConfigError
        Both members of a pair stated in this layer (naming both).
    """
    items = list(items)
    keys = [(dotted(parts), value) for parts, value in items]
    _check_layer(keys, where)
    here = {k for k, _ in keys}
    machine_before = _machine_of(data)
    for (parts, value), (key, _) in zip(items, keys, strict=True):
        _check_element_of_twin(data, parts)
        set_path(data, parts, value)
        pair = pair_of(key)
        if pair is None or value is None:
            continue
        for twin in pair.twins(key):
            node, name = _section(data, twin)
            if twin in here or node is None or name not in node:
                continue
            old = node.pop(name)
            if _is_set(twin, old) and not pair.quiet:
                warnings.warn(
                    ConfigWarning(key, f"replaces {twin} = {old!r} of the scenario underneath"),
                    stacklevel=2,
                )
    _warn_machine_replaced(data, machine_before, here)


def _check_element_of_twin(data: dict, parts: tuple) -> None:
    """An element of a profile (``control.speed_ref_rpm.changes[0].to``) whose scenario states
    the profile by its twin of the other unit (``control.speed_ref_pu``): one line naming the
    twin's element to set instead (a per-unit preset's profile is not converted to rpm)."""
    if len(parts) < 3:
        return
    key = dotted(parts[:2])
    pair = pair_of(key)
    node, name = _section(data, key)
    if pair is None or node is None or name in node:
        return
    for twin in pair.twins(key):
        t_node, t_name = _section(data, twin)
        if t_node is not None and isinstance(t_node.get(t_name), dict):
            rest = dotted(parts[2:]).replace(".[", "[")
            raise ConfigError(
                dotted(parts),
                f"the scenario states this profile as {twin} (per-unit of {pair.base}): set "
                f"{twin}.{rest}, or the whole {key}",
            )


def _machine_of(data: dict) -> tuple:
    """What names the scenario's parameter set: ``machine.preset`` and ``machine.file``."""
    node = data.get("machine") if isinstance(data, dict) else None
    if not isinstance(node, dict):
        return (None, None)
    return (node.get("preset"), node.get("file"))


def _warn_machine_replaced(data: dict, before: tuple, here: set[str]) -> None:
    """One warning when this layer replaced the machine (``machine.preset`` / ``file``) under
    absolute settings of the layer underneath (:data:`PAIRS`' absolute members): they were
    tuned for the machine underneath and stay as given, their per-unit twins would follow."""
    after = _machine_of(data)
    if after == before or before == (None, None):
        return
    stale = []
    for p in (p for p in PAIRS if p.machine_bound):
        for key, twin in zip(p.absolute, p.per_unit, strict=True):
            node, name = _section(data, key)
            if key in here or node is None or name not in node:
                continue
            if _is_set(key, node[name]):
                stale.append((key, node[name], twin))
    model = data.get("controller_model")
    if isinstance(model, dict) and model.get("ideal") is True:
        model = None  # derived from the new machine when the scenario is read
    # the measured tables themselves (a scenario written out in full states the mode keys and
    # empty tables too: those were not commissioned on anything)
    tables = sorted(
        k
        for k, v in (model.items() if isinstance(model, dict) else ())
        if isinstance(v, list | tuple) and len(v) > 0
    )
    tables = [t for t in tables if f"controller_model.{t}" not in here]
    if not stale and not tables:
        return
    was = before[0] if before[0] is not None else before[1]
    now = after[0] if after[0] is not None else after[1]
    parts = []
    if stale:
        listed = ", ".join(f"{k} = {v!r}" for k, v, _ in stale[:6])
        more = f" and {len(stale) - 6} more" if len(stale) > 6 else ""
        twins = ", ".join(t for _, _, t in stale[:6])
        parts.append(
            f"absolute settings {listed}{more} stay as given (state them per-unit to follow "
            f"the machine: {twins})"
        )
    if tables:
        parts.append(
            f"the controller_model tables ({', '.join(tables)}) are {was!s}'s (run `imdrive "
            "commission` on the new machine, or clear [controller_model])"
        )
    warnings.warn(
        ConfigWarning("machine", f"{now!s} replaces {was!s}: " + "; ".join(parts)),
        stacklevel=3,
    )


def apply_overrides(data: dict, overrides, where: str = "--set") -> None:
    """Apply a list of ``key.path=value`` strings as one layer (:func:`set_layer`)."""
    set_layer(data, [parse_override(ov) for ov in overrides], where)


def _value(sc, key: str):
    """``key``'s value in ``sc``; None where it was derived (``_<name>_auto``, a twin's)."""
    node = sc
    *head, name = key.split(".")
    for p in head:
        node = getattr(node, p)
    return None if getattr(node, f"_{name}_auto", False) else getattr(node, name)


def check_pairs(sc) -> None:
    """Refuse a scenario that states both members of a pair (:data:`PAIRS`), naming both; a
    pair whose ``both`` names the member used is warned about (deprecated).

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Raises
    ------
    ConfigError
        Both members of a strict pair stated.
    """
    for p in PAIRS:
        a = [k for k in p.absolute if _is_set(k, _value(sc, k))]
        u = [k for k in p.per_unit if _is_set(k, _value(sc, k))]
        if not (a and u):
            continue
        if p.both == "error":
            raise ConfigError(u[0], f"set {a[0]} or {u[0]}, not both")
        used = u[0] if p.both == "per_unit" else a[0]
        warnings.warn(
            ConfigWarning(
                u[0],
                f"{a[0]} and {u[0]} both set: {used} is used (deprecated: set one of them)",
            ),
            stacklevel=4,
        )
