"""Dotted-key overrides (``control.speed_ref_rpm=1500``): one mechanism for ``--set``, sweeps
and :meth:`~imdrive.config.scenario.Scenario.with_overrides`, and the walk over the scenario
file's keys they check paths against.

The keys are read off the settings classes, starting at the root class of the file,
:class:`~imdrive.config.scenario.Scenario`, which registers itself here with
:func:`scenario_root` when it is defined (so this module does not import it and ``Scenario``
applies overrides without an import cycle). :mod:`imdrive.config.schema` re-exports the walk.
"""

from __future__ import annotations

import dataclasses
import functools
import re
import tomllib
import typing
from dataclasses import dataclass, fields, is_dataclass
from typing import Any

from pydantic.fields import FieldInfo

from imdrive.config.deprecated_keys import is_deprecated
from imdrive.config.profiles import Profile
from imdrive.errors import ConfigError

__all__ = [
    "FILE_PATHS",
    "Key",
    "_schema_allows",
    "apply_override",
    "dotted",
    "is_setting",
    "is_table_class",
    "key_path",
    "parse_override",
    "parse_toml",
    "scenario_keys",
    "scenario_root",
    "set_path",
    "setting_paths",
    "table_paths",
]

_ROOT: list[type] = []


def scenario_root(cls: type) -> type:
    """Class decorator: ``cls`` is the root table of a scenario file (its fields are the
    top-level keys and sections), the class :func:`scenario_keys` walks from.

    Parameters
    ----------
    cls : type
        The settings class of a whole scenario (:class:`~imdrive.config.scenario.Scenario`).

    Returns
    -------
    type
        ``cls`` itself.
    """
    _ROOT[:] = [cls]
    for f in (scenario_keys, setting_paths, table_paths):
        f.cache_clear()
    return cls


def _root() -> type:
    if not _ROOT:  # imdrive.config imports config.scenario, which registers the root
        raise RuntimeError("imdrive.config.scenario has not registered the scenario class")
    return _ROOT[0]


def _check_override_list(overrides) -> None:
    """The overrides must be a list or tuple of ``key=value`` strings: a single string would
    be read one character at a time, None or a number is not a list, and bytes are not text."""
    if isinstance(overrides, str):
        raise ConfigError(
            "overrides",
            f"must be a list of 'key=value' strings, not a string (write [{overrides!r}])",
        )
    if not isinstance(overrides, list | tuple):
        raise ConfigError(
            "overrides",
            f"must be a list of 'key=value' strings, got {type(overrides).__name__}",
        )
    for k, ov in enumerate(overrides):
        if not isinstance(ov, str):
            raise ConfigError(
                f"overrides[{k}]", f"must be a 'key=value' string, got {type(ov).__name__}"
            )


def _to_plain(obj):
    if isinstance(obj, Profile):
        return obj.to_toml_value()
    if is_dataclass(obj):
        return {f.name: _to_plain(getattr(obj, f.name)) for f in fields(obj)}
    return obj


def _convert(tp, val, path: str):
    """The value for the field at ``path``, as :mod:`imdrive.sweep` passes it to
    ``dataclasses.replace``.

    The settings classes validate their fields themselves: the value is returned as is and the
    constructor that receives it checks and converts it, naming the same ``path``.
    """
    return val


# ------------------------------------------------------------------------------------------
# The file's keys, read off the settings classes (one walk for --set, sweeps, docs, schema),
# and the one override mechanism.

#: Where a field of the Scenario object lives in the file.
FILE_PATHS = {"machine_preset": ("machine", "preset")}


@dataclass(frozen=True)
class Key:
    """One key of a scenario file.

    ``path`` is its dotted path (``("plant", "thermal", "tau1_s")``); ``owner`` the settings
    class that holds the field and ``name`` the field's name there; ``info`` its pydantic
    field (description, unit, constraints); ``hint`` its type without metadata (``float``,
    ``Literal[...]``, ``Profile | None``, a settings class); ``default`` its default
    (``dataclasses.MISSING`` for a machine field, which comes from the preset); ``table`` the
    settings class when the key is a table (a section or ``plant.thermal``).
    """

    path: tuple[str, ...]
    owner: type
    name: str
    info: FieldInfo
    hint: Any
    default: Any
    table: type | None

    @property
    def dotted(self) -> str:
        return ".".join(self.path)


def is_table_class(tp) -> bool:
    """Whether ``tp`` is a settings class (a pydantic dataclass), i.e. a table in the file."""
    return isinstance(tp, type) and hasattr(tp, "__pydantic_fields__")


def _fields(cls, prefix: tuple[str, ...]):
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        path = FILE_PATHS.get(f.name, (*prefix, f.name)) if cls is _root() else (*prefix, f.name)
        hint = hints[f.name]
        table = hint if is_table_class(hint) else None
        yield Key(path, cls, f.name, cls.__pydantic_fields__[f.name], hint, f.default, table)


@functools.cache
def scenario_keys() -> tuple[Key, ...]:
    """Every key of a scenario file, tables included, in file order (sections as in
    :data:`~imdrive.config.scenario.SECTIONS`, ``[machine]`` first with ``preset``)."""
    top = {k.name: k for k in _fields(_root(), ())}
    out = [top["name"], top["description"]]
    machine = top["machine"]
    out.append(machine)
    out.append(top["machine_preset"])
    for k in _fields(machine.table, ("machine",)):
        out.append(dataclasses.replace(k, default=dataclasses.MISSING))

    def walk(key: Key):
        out.append(key)
        for sub in _fields(key.table, key.path):
            if sub.table is not None:
                walk(sub)
            else:
                out.append(sub)

    for key in top.values():  # the sections, in the order Scenario declares them
        if key.table is not None and key.name != "machine":
            walk(key)
    return tuple(out)


@functools.cache
def setting_paths() -> frozenset[tuple[str, ...]]:
    """Paths a single value may be set at: every key except the top-level tables."""
    return frozenset(k.path for k in scenario_keys() if not (k.table and len(k.path) == 1))


@functools.cache
def table_paths() -> frozenset[tuple[str, ...]]:
    """Paths of the tables of the file (``("machine",)``, ``("plant", "thermal")``, ...)."""
    return frozenset(k.path for k in scenario_keys() if k.table is not None)


def _schema_allows(path: list[str]) -> bool:
    """Whether a dotted override path names a field of the scenario schema.

    A field is a value (``simulation.Ts_s``, ``machine.preset``) or a table inside a section
    (``plant.thermal``); a whole section (``simulation``) is not one. The paths are read off
    the settings classes (:func:`scenario_keys`). A plug-in estimator's setting
    (``plugins.settings.NAME.KEY``) is allowed here and checked when the scenario is validated,
    after its module is imported.
    """
    if len(path) == 4 and tuple(path[:2]) == ("plugins", "settings"):
        return True
    return tuple(path) in setting_paths() or is_deprecated(path)


def is_setting(parts) -> bool:
    """Whether the dotted path ``parts`` names a field of the scenario schema."""
    return bool(parts) and all(parts) and _schema_allows(list(parts))


def parse_toml(text: str, field: str, what: str = "") -> dict:
    """Parse TOML text from the user (a scenario, sweep or machine file, an override's value).

    Every way it can be bad is a :class:`ConfigError` naming ``field``: invalid TOML, and
    arrays or inline tables nested so deeply that the parser runs out of stack (a
    ``RecursionError`` is bad input here, not a bug). A UTF-8 byte-order mark is skipped.

    Parameters
    ----------
    text : str
        The TOML text.
    field : str
        What the error names (``"scenario"``, ``"sweep"``, ``"machine.file"``).
    what : str
        Where the text comes from, for the message (a file name), or ``""``.
    """
    where = f" in {what}" if what else ""
    if not isinstance(text, str):  # parse_sweep(None), from_toml(b"...")
        raise ConfigError(field, f"must be TOML text (a str), got {type(text).__name__}")
    try:
        return tomllib.loads(text.removeprefix("\ufeff"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(field, f"invalid TOML{where}: {exc}") from None
    except RecursionError:
        raise ConfigError(
            field, f"invalid TOML{where}: arrays or tables nested too deeply to read"
        ) from None


_INDEXED = re.compile(r"^([A-Za-z_][\w-]*)((?:\[\d+\])*)$")
#: the keys inside a profile written as a table (``{initial, changes = [{at, to, over}]}``
#: or ``{points = [[t, v], ...]}``) an override may reach into
PROFILE_PARTS = ("initial", "changes", "at", "to", "over", "points")


def _split_key(key: str) -> tuple:
    """``"a.changes[0].to"`` -> ``("a", "changes", 0, "to")``."""
    parts: list = []
    for token in key.split("."):
        m = _INDEXED.match(token)
        if m is None:
            if "[" in token:
                raise ConfigError(key, f"{token!r}: an index is written name[0]")
            parts.append(token)
            continue
        parts.append(m.group(1))
        parts.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return tuple(parts)


def _is_profile_key(parts) -> bool:
    key = next((k for k in scenario_keys() if k.path == tuple(parts)), None)
    return key is not None and "Profile" in str(key.hint)


def _profile_element(parts) -> bool:
    """Whether ``parts`` reaches into a profile: a profile key, then its table's keys and
    list indices (``control.speed_ref_rpm.changes[0].to``)."""
    for n in range(len(parts) - 1, 0, -1):
        head, rest = parts[:n], parts[n:]
        if all(isinstance(p, str) for p in head) and _is_profile_key(head):
            return all(isinstance(p, int) or p in PROFILE_PARTS for p in rest)
    return False


def key_path(key: str, field: str | None = None) -> tuple:
    """The path of a scenario key written ``a.b.c`` or into a profile's element
    (``control.speed_ref_rpm.changes[0].to`` -> ``("control", "speed_ref_rpm", "changes", 0,
    "to")``); a key that names no setting raises :class:`ConfigError` naming ``field`` (default
    the key)."""
    parts = _split_key(key)
    if not (all(isinstance(p, str) for p in parts) and is_setting(parts)) and not (
        _profile_element(parts)
    ):
        raise ConfigError(
            key if field is None else field,
            "no such setting (see 'imdrive show PRESET' for the keys)",
        )
    return parts


def parse_override(spec: str) -> tuple[tuple, object]:
    """Split ``key.path=value`` into the path and the value (parsed as a TOML value).

    A value that is not valid TOML is taken as a string, so ``control.speed_feedback=mras``
    needs no quotes. The path may reach into one element of a profile written as a table:
    ``control.speed_ref_rpm.changes[0].to=300`` (indices from 0; the path then holds ints).
    """
    if not isinstance(spec, str):
        raise ConfigError(
            "overrides", f"each override must be a 'key=value' string, got {type(spec).__name__}"
        )
    if not spec.isprintable():
        # a line break would start a second TOML line that the value's parse drops
        raise ConfigError(
            "--set",
            f"{spec[:60]!r} holds a line break or another control character: give one "
            "key=value per --set (in a string value write \\n)",
        )
    if "=" not in spec:
        raise ConfigError(spec, "override must look like key.path=value")
    key, raw = spec.split("=", 1)
    key = key.strip()
    if not key:
        raise ConfigError("--set", f"{spec!r}: the key before '=' is empty")
    parts = key_path(key)
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    except RecursionError:
        raise ConfigError(key, "the value is nested too deeply") from None
    return parts, value


def set_path(data: dict, parts, value) -> None:
    """Set the value at the dotted path ``parts`` of a TOML-shaped scenario dictionary.

    The one override mechanism: ``--set`` and every sweep axis go through it, and the
    scenario is validated once afterwards (:meth:`Scenario.from_dict`).
    """
    key = dotted(parts)
    if any(isinstance(p, int) for p in parts):
        _set_element(data, parts, value, key)
        return
    node = data
    for p in parts[:-1]:
        nxt = node.setdefault(p, {})
        if not isinstance(nxt, dict):
            raise ConfigError(key, f"{p} is not a table")
        node = nxt
    node[parts[-1]] = value


def dotted(parts) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else p)
    return out


def _changes_form(profile):
    """A profile in the file's ``{initial, changes}`` form: a number or ``{points = ...}`` is
    rewritten (a step where two points share a time, a ramp between two values, a hold
    dropped), a profile already in that form is returned as it is."""
    if isinstance(profile, int | float) and not isinstance(profile, bool):
        return {"initial": profile, "changes": []}
    if not (isinstance(profile, dict) and "points" in profile):
        return profile
    pts = [tuple(p) for p in profile["points"]]
    changes = []
    for (t0, v0), (t1, v1) in zip(pts, pts[1:], strict=False):
        if v1 == v0:
            continue
        changes.append({"at": t1, "to": v1} if t1 == t0 else {"at": t0, "to": v1, "over": t1 - t0})
    return {"initial": pts[0][1], "changes": changes}


def _set_element(data: dict, parts, value, key: str) -> None:
    """Set one element inside a profile the file writes as a table; every step must exist
    (an element is changed, never created)."""
    node = data
    for n, p in enumerate(parts[:-1]):
        here = dotted(parts[: n + 1])
        if isinstance(p, int):
            if not isinstance(node, list) or p >= len(node):
                size = len(node) if isinstance(node, list) else 0
                raise ConfigError(key, f"{here}: no such element (the list has {size})")
            node = node[p]
        else:
            nxt = parts[n + 1]
            if isinstance(node, dict) and nxt in ("initial", "changes") and p in node:
                node[p] = _changes_form(node[p])  # a profile as points or a number
            if not isinstance(node, dict) or p not in node:
                raise ConfigError(
                    key,
                    f"{here} is not in the scenario as a table: set the whole profile "
                    "(e.g. {initial = 0, changes = [{at = 0.5, to = 1000, over = 1}]})",
                )
            node = node[p]
    last = parts[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or last >= len(node):
            raise ConfigError(key, "no such element")
        node[last] = value
    elif isinstance(node, dict) and last in node:
        node[last] = value
    elif isinstance(node, dict) and last == "over":  # a step becomes a ramp
        node[last] = value
    else:
        raise ConfigError(key, f"{last!r} is not set in that element")


def apply_override(data: dict, spec: str) -> None:
    """Apply ``key.path=value`` to a scenario dictionary (see :func:`parse_override`)."""
    parts, value = parse_override(spec)
    set_path(data, parts, value)


def override_items(overrides) -> list[tuple[tuple[str, ...], object]]:
    """``(key path, value)`` pairs of ``--set`` strings or of a ``{dotted key: value}`` dict.

    Parameters
    ----------
    overrides : list of str or dict
        ``["control.speed_ref_rpm=1500", ...]`` (values parsed as TOML) or
        ``{"control.speed_ref_rpm": 1500, ...}``.

    Returns
    -------
    list of tuple
        In the given order.

    Raises
    ------
    ConfigError
        A key that is not a dotted str or names no setting, or a malformed string.
    """
    if not isinstance(overrides, dict):
        _check_override_list(overrides)
        return [parse_override(o) for o in overrides]
    items = []
    for key, value in overrides.items():
        if not isinstance(key, str):
            raise ConfigError("overrides", f"a key must be a dotted str, got {type(key).__name__}")
        parts = tuple(key.split("."))
        if not is_setting(parts):
            raise ConfigError(str(key), "no such setting")
        items.append((parts, value))
    return items
