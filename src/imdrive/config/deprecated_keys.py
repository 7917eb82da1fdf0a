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

#: ``(section, key)`` -> ``asks_for_the_rule(data, value)``: whether a deprecated key's value
#: asks for what its rule does anyway (its old default, which a scenario written out in full
#: by an earlier release carries): dropped without a warning.
DEPRECATED_SILENT_IF: dict[tuple[str, str], object] = {}

#: ``(section, key, old value)`` -> ``(new value, why)``.
DEPRECATED_VALUES: dict[tuple[str, str, object], tuple[object, str]] = {}

#: ``(section, key)`` -> its per-unit twin: absolute spellings that still act (through
#: :mod:`imdrive.config.pairs`) with a warning, listed apart from the tables.
DEPRECATED_TWINS: dict[tuple[str, str], str] = {}

#: ``(section, key)`` -> the value of a deprecated twin that states nothing (its old default,
#: which a scenario written out in full carries: ``injection.amplitude_A = 0.0``): not warned.
TWIN_UNSET: dict[tuple[str, str], object] = {}


def deprecated_key(section: str, key: str, why: str, silent_if=None) -> None:
    """Register ``[section] key`` as deprecated: accepted, dropped, warned with ``why``.
    ``silent_if(data, value)``: true when the value asks for what the rule does (the
    scenario's TOML-shaped ``data``), dropped then without a warning."""
    DEPRECATED_KEYS[(section, key)] = why
    if silent_if is not None:
        DEPRECATED_SILENT_IF[(section, key)] = silent_if


def deprecated_value(section: str, key: str, old, new, why: str) -> None:
    """Register the value ``old`` of ``[section] key`` as deprecated: replaced by ``new``."""
    DEPRECATED_VALUES[(section, key, old)] = (new, why)


def deprecated_twin(section: str, key: str, twin: str, unset=None) -> None:
    """Register ``[section] key`` as the deprecated absolute spelling of ``[section] twin``:
    it still acts, with a warning, and is listed apart in docs/scenarios.md. ``unset``: a value
    besides None that states nothing (its old default), left without a warning."""
    DEPRECATED_TWINS[(section, key)] = twin
    if unset is not None:
        TWIN_UNSET[(section, key)] = unset


def is_deprecated(path) -> bool:
    """Whether the dotted path ``path`` (a tuple of names) is a deprecated key that no longer
    acts (a deprecated twin is a setting still: :data:`DEPRECATED_TWINS`)."""
    return len(path) == 2 and tuple(path) in DEPRECATED_KEYS


def is_listed_apart(path) -> bool:
    """Whether docs/scenarios.md lists the key ``path`` in its deprecated section."""
    return len(path) == 2 and (tuple(path) in DEPRECATED_KEYS or tuple(path) in DEPRECATED_TWINS)


def drop_deprecated(data: dict) -> dict:
    """``data`` (a scenario's TOML-shaped dictionary) without its deprecated keys and with its
    deprecated values replaced, one warning each; ``data`` itself is not changed."""
    out = data
    for (section, key), why in DEPRECATED_KEYS.items():
        table = out.get(section)
        if isinstance(table, dict) and key in table:
            silent_if = DEPRECATED_SILENT_IF.get((section, key))
            # None states nothing (a summary.json writes an unset key as null)
            quiet = table[key] is None or (silent_if is not None and silent_if(data, table[key]))
            out = {**out, section: {k: v for k, v in table.items() if k != key}}
            if quiet:
                continue
            warnings.warn(
                ConfigWarning(
                    f"{section}.{key}",
                    f"deprecated, no longer has any effect and is refused from imdrive "
                    f"{REMOVED_IN}: {why}",
                ),
                stacklevel=3,
            )
    for (section, key), twin in DEPRECATED_TWINS.items():
        table = out.get(section)
        value = table.get(key) if isinstance(table, dict) else None
        if value is not None and not _states_nothing(section, key, value):
            warnings.warn(
                ConfigWarning(
                    f"{section}.{key}",
                    f"deprecated, refused from imdrive {REMOVED_IN}: state it per-unit of the "
                    f"machine as {section}.{twin} (it still acts until then)",
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


def _states_nothing(section: str, key: str, value) -> bool:
    unset = TWIN_UNSET.get((section, key))
    return unset is not None and not isinstance(value, bool) and value == unset


def markdown_lines() -> list[str]:
    """The section "Deprecated keys" of docs/scenarios.md: every deprecated key and value,
    why it no longer acts and what replaces it."""
    if not (DEPRECATED_KEYS or DEPRECATED_VALUES or DEPRECATED_TWINS):
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
    if DEPRECATED_TWINS:
        lines += [
            "",
            "Absolute spellings of per-unit settings: they still act, with a warning, and are "
            f"refused from imdrive {REMOVED_IN}.",
            "",
            "| key | state it per-unit of the machine as |",
            "|---|---|",
        ]
        lines += [f"| `{s}.{k}` | `{s}.{t}` |" for (s, k), t in DEPRECATED_TWINS.items()]
    return lines + [""]


def _toml(value) -> str:
    return f'"{value}"' if isinstance(value, str) else str(value)
