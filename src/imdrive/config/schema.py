"""The scenario file's keys, read off the pydantic settings classes: one walk for all users.

:func:`scenario_keys` lists every key a scenario file (and ``--set``, and a sweep axis) may
name, with its field metadata; :mod:`imdrive.config.overrides` checks paths against it and
:mod:`imdrive.config.docs` writes ``docs/scenarios.md`` from it. :func:`json_schema` is the
JSON Schema of a scenario file, from the same classes.

The file differs from the :class:`~imdrive.config.scenario.Scenario` object in one place: the
object's ``machine_preset`` is written ``preset`` inside ``[machine]``, and there every
machine field is optional (it defaults to the preset's value).
"""

from __future__ import annotations

import dataclasses
import functools
import typing
from dataclasses import dataclass
from typing import Any

from pydantic import TypeAdapter
from pydantic.fields import FieldInfo
from pydantic.json_schema import GenerateJsonSchema

from imdrive.config.machine import machine_presets
from imdrive.config.profiles import Profile
from imdrive.config.scenario import DEFAULT_MACHINE_PRESET, SECTIONS, Scenario

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
        path = FILE_PATHS.get(f.name, (*prefix, f.name)) if cls is Scenario else (*prefix, f.name)
        hint = hints[f.name]
        table = hint if is_table_class(hint) else None
        yield Key(path, cls, f.name, cls.__pydantic_fields__[f.name], hint, f.default, table)


@functools.cache
def scenario_keys() -> tuple[Key, ...]:
    """Every key of a scenario file, tables included, in file order (sections as in
    :data:`~imdrive.config.scenario.SECTIONS`, ``[machine]`` first with ``preset``)."""
    top = {k.name: k for k in _fields(Scenario, ())}
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

    for name in SECTIONS:
        walk(top[name])
    return tuple(out)


@functools.cache
def setting_paths() -> frozenset[tuple[str, ...]]:
    """Paths a single value may be set at: every key except the top-level tables."""
    return frozenset(k.path for k in scenario_keys() if not (k.table and len(k.path) == 1))


@functools.cache
def table_paths() -> frozenset[tuple[str, ...]]:
    """Paths of the tables of the file (``("machine",)``, ``("plant", "thermal")``, ...)."""
    return frozenset(k.path for k in scenario_keys() if k.table is not None)


# ------------------------------------------------------------------------------------------
# JSON Schema


class _FileSchema(GenerateJsonSchema):
    """Defaults written in file form (a constant profile is a number)."""

    def encode_default(self, dft):
        if isinstance(dft, Profile):
            return dft.to_toml_value()
        return super().encode_default(dft)


def _ref(prop: dict) -> str | None:
    """Name of the definition a property refers to (``$ref``, or ``allOf: [{$ref}]`` as older
    pydantic versions write it next to a description)."""
    ref = prop.get("$ref") or (prop.get("allOf") or [{}])[0].get("$ref")
    return ref.split("/")[-1] if ref else None


def json_schema() -> dict:
    """JSON Schema (draft 2020-12) of a scenario file, for editors that validate TOML."""
    schema = TypeAdapter(Scenario).json_schema(schema_generator=_FileSchema)
    defs = schema["$defs"]
    props = schema["properties"]
    preset = props.pop("machine_preset")
    # [machine]: the preset's name and any field overriding it (none required)
    machine = defs[_ref(props["machine"])]
    machine.pop("required", None)
    names = sorted(machine_presets())
    machine["properties"] = {
        "preset": {
            "enum": names,
            "default": DEFAULT_MACHINE_PRESET,
            "description": preset["description"],
            "title": "Preset",
        },
        **machine["properties"],
    }
    for d in [schema, *defs.values()]:  # a table's default is its keys' defaults
        for prop in d.get("properties", {}).values():
            if _ref(prop) not in (None, "Profile"):
                prop.pop("default", None)
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "imdrive scenario",
        "description": (
            "A scenario file of imdrive (docs/scenarios.md). Every key is optional; "
            "[machine] starts from a published parameter set."
        ),
        **{k: v for k, v in schema.items() if k not in ("title", "description")},
    }
