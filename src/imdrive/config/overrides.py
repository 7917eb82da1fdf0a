"""Dotted-key overrides (``control.speed_ref_rpm=1500``): one mechanism for ``--set`` and sweeps."""

from __future__ import annotations

import tomllib
import typing
from dataclasses import is_dataclass

from imdrive.config.machine import MachineParams
from imdrive.config.scenario import SECTIONS
from imdrive.errors import ConfigError


def _schema_allows(path: list[str]) -> bool:
    """Whether a dotted override path names a field of the scenario schema."""
    if len(path) == 1:
        return path[0] in ("name", "description")
    head, rest = path[0], path[1:]
    if head == "machine":
        return len(rest) == 1 and (
            rest[0] == "preset" or rest[0] in typing.get_type_hints(MachineParams)
        )
    cls = SECTIONS.get(head)
    while cls is not None and rest:
        hints = typing.get_type_hints(cls)
        if rest[0] not in hints:
            return False
        tp = hints[rest[0]]
        rest = rest[1:]
        if not rest:
            return True
        cls = tp if is_dataclass(tp) else None
    return False


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
