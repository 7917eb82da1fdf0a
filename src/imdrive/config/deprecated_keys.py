"""Scenario keys and values that no longer have an effect, accepted with a warning.

A file, a ``--set`` or a ``summary.json`` written for an earlier release keeps working: each
deprecated key is dropped before the scenario is validated (:func:`drop_deprecated`), with a
:class:`~imdrive.errors.ConfigWarning` that names the key and says why it no longer acts and
what replaces it; a deprecated value (``compensator.step_law = "adaptive"``) is replaced by
its successor with the same kind of warning. docs/scenarios.md lists them apart, in a section
of their own (:func:`markdown_lines`). They are refused from imdrive :data:`REMOVED_IN` on.
"""

from __future__ import annotations

import warnings

from imdrive.errors import ConfigWarning

#: The release that refuses them.
REMOVED_IN = "0.3"

#: ``(section, key)`` -> why it has no effect now, and what replaces it.
DEPRECATED_KEYS: dict[tuple[str, str], str] = {}

#: ``(section, key, old value)`` -> ``(new value, why)``.
DEPRECATED_VALUES: dict[tuple[str, str, object], tuple[object, str]] = {}


def deprecated_key(section: str, key: str, why: str) -> None:
    """Register ``[section] key`` as deprecated: accepted, dropped, warned with ``why``."""
    DEPRECATED_KEYS[(section, key)] = why


def deprecated_value(section: str, key: str, old, new, why: str) -> None:
    """Register the value ``old`` of ``[section] key`` as deprecated: replaced by ``new``."""
    DEPRECATED_VALUES[(section, key, old)] = (new, why)


def is_deprecated(path) -> bool:
    """Whether the dotted path ``path`` (a tuple of names) is a deprecated key."""
    return len(path) == 2 and tuple(path) in DEPRECATED_KEYS


def drop_deprecated(data: dict) -> dict:
    """``data`` (a scenario's TOML-shaped dictionary) without its deprecated keys and with its
    deprecated values replaced, one warning each; ``data`` itself is not changed."""
    out = data
    for (section, key), why in DEPRECATED_KEYS.items():
        table = out.get(section)
        if isinstance(table, dict) and key in table:
            out = {**out, section: {k: v for k, v in table.items() if k != key}}
            warnings.warn(
                ConfigWarning(
                    f"{section}.{key}",
                    f"deprecated, no longer has any effect and is refused from imdrive "
                    f"{REMOVED_IN}: {why}",
                ),
                stacklevel=3,
            )
    for (section, key, old), (new, why) in DEPRECATED_VALUES.items():
        table = out.get(section)
        if isinstance(table, dict) and table.get(key) == old:
            out = {**out, section: {**table, key: new}}
            warnings.warn(
                ConfigWarning(
                    f"{section}.{key}",
                    f"{old!r} is deprecated and runs as {new!r} (refused from imdrive "
                    f"{REMOVED_IN}): {why}",
                ),
                stacklevel=3,
            )
    return out


def markdown_lines() -> list[str]:
    """The section "Deprecated keys" of docs/scenarios.md: every deprecated key and value,
    why it no longer acts and what replaces it."""
    if not (DEPRECATED_KEYS or DEPRECATED_VALUES):
        return []
    lines = [
        "## Deprecated keys",
        "",
        "Accepted with a warning and without effect; refused from imdrive "
        f"{REMOVED_IN}. They are not part of the tables above.",
        "",
        "| key | why it has no effect, and what replaces it |",
        "|---|---|",
    ]
    for (section, key, old), (new, why) in DEPRECATED_VALUES.items():
        lines.append(f"| `{section}.{key} = {_toml(old)}` | runs as `{_toml(new)}`: {why} |")
    for (section, key), why in DEPRECATED_KEYS.items():
        lines.append(f"| `{section}.{key}` | {why} |")
    return lines + [""]


def _toml(value) -> str:
    return f'"{value}"' if isinstance(value, str) else str(value)
