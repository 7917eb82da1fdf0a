"""Dotted-key overrides (``control.speed_ref_rpm=1500``): one mechanism for ``--set`` and sweeps."""

from __future__ import annotations

import tomllib

from imdrive.config.schema import setting_paths
from imdrive.errors import ConfigError


def _schema_allows(path: list[str]) -> bool:
    """Whether a dotted override path names a field of the scenario schema.

    A field is a value (``simulation.Ts_s``, ``machine.preset``) or a table inside a section
    (``plant.thermal``); a whole section (``simulation``) is not one. The paths are read off
    the settings classes (:func:`imdrive.config.schema.scenario_keys`).
    """
    return tuple(path) in setting_paths()


def is_setting(parts) -> bool:
    """Whether the dotted path ``parts`` names a field of the scenario schema."""
    return bool(parts) and all(parts) and _schema_allows(list(parts))


def parse_override(spec: str) -> tuple[tuple[str, ...], object]:
    """Split ``key.path=value`` into the path and the value (parsed as a TOML value).

    A value that is not valid TOML is taken as a string, so ``control.speed_feedback=mras``
    needs no quotes.
    """
    if "=" not in spec:
        raise ConfigError(spec, "override must look like key.path=value")
    key, raw = spec.split("=", 1)
    key = key.strip()
    if not key:
        raise ConfigError("--set", f"{spec!r}: the key before '=' is empty")
    parts = tuple(key.split("."))
    if not is_setting(parts):
        raise ConfigError(key, "no such setting (see 'imdrive show PRESET' for the keys)")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return parts, value


def set_path(data: dict, parts, value) -> None:
    """Set the value at the dotted path ``parts`` of a TOML-shaped scenario dictionary.

    The one override mechanism: ``--set`` and every sweep axis go through it, and the
    scenario is validated once afterwards (:meth:`Scenario.from_dict`).
    """
    key = ".".join(parts)
    node = data
    for p in parts[:-1]:
        nxt = node.setdefault(p, {})
        if not isinstance(nxt, dict):
            raise ConfigError(key, f"{p} is not a table")
        node = nxt
    node[parts[-1]] = value


def apply_override(data: dict, spec: str) -> None:
    """Apply ``key.path=value`` to a scenario dictionary (see :func:`parse_override`)."""
    parts, value = parse_override(spec)
    set_path(data, parts, value)
