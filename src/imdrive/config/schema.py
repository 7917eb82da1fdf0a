"""The scenario file's keys, read off the pydantic settings classes: one walk for all users.

:func:`scenario_keys` (defined in :mod:`imdrive.config.overrides`, which checks override
paths against it, and re-exported here) lists every key a scenario file (and ``--set``, and a
sweep axis) may name, with its field metadata; :mod:`imdrive.config.docs` writes
``docs/scenarios.md`` from it. :func:`json_schema` is the
JSON Schema of a scenario file, from the same classes.

The file differs from the :class:`~imdrive.config.scenario.Scenario` object in one place: the
object's ``machine_preset`` is written ``preset`` inside ``[machine]``, and there every
machine field is optional (it defaults to the preset's value).
"""

from __future__ import annotations

from pydantic import TypeAdapter
from pydantic.json_schema import GenerateJsonSchema

from imdrive.config.machine import machine_presets

# the walk lives in imdrive.config.overrides, re-exported here
from imdrive.config.overrides import (
    FILE_PATHS,
    Key,
    is_table_class,
    scenario_keys,
    setting_paths,
    table_paths,
)
from imdrive.config.profiles import Profile
from imdrive.config.scenario import DEFAULT_MACHINE_PRESET, Scenario

__all__ = [
    "FILE_PATHS",
    "Key",
    "is_table_class",
    "json_schema",
    "scenario_keys",
    "setting_paths",
    "table_paths",
]

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
