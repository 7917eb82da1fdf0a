"""A small TOML writer for scenario dictionaries (the standard library only reads TOML).

Writes what :meth:`imdrive.config.scenario.Scenario.to_dict` holds: strings, booleans,
integers, floats (``inf``, ``nan`` included), lists, and tables. Top-level tables become
``[section]`` headers; a table inside a section becomes an inline table when it holds only
values (a profile ``{ points = [...] }``), a ``[section.sub]`` header otherwise. ``None`` (an
unset optional setting) is written as a comment line, which reads back as unset.
"""

from __future__ import annotations

import math
import re

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(k: str) -> str:
    return k if _BARE.match(k) else _string(k)


def _string(s: str) -> str:
    out = s.replace("\\", "\\\\").replace('"', '\\"')
    out = "".join(c if c.isprintable() else f"\\u{ord(c):04x}" for c in out)
    return f'"{out}"'


def value(v) -> str:
    """One TOML value (no tables of tables)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, list | tuple):
        return "[" + ", ".join(value(x) for x in v if x is not None) + "]"
    if isinstance(v, dict):
        items = [f"{_key(k)} = {value(x)}" for k, x in v.items() if x is not None]
        return "{ " + ", ".join(items) + " }" if items else "{}"
    raise TypeError(f"cannot write {type(v).__name__} as TOML")


def _twin_rule(path: list[str], k: str, d: dict) -> str:
    """Why an unset key takes its value: its per-unit (or absolute) twin in the same table
    when that one is set (:mod:`imdrive.config.pairs`), else its documented default."""
    from imdrive.config.pairs import pair_of

    pair = pair_of(".".join([*path, k]))
    if pair is not None:
        for twin in pair.twins(".".join([*path, k])):
            *head, name = twin.split(".")
            if head == path and d.get(name) is not None:
                return f"taken from its twin {name}"
    return "its documented default applies"


def _table(lines: list[str], path: list[str], d: dict, resolved: dict) -> None:
    subs = []
    body = []
    for k, v in d.items():
        if v is None:
            here = resolved.get(".".join([*path, k]))
            rule = _twin_rule(path, k, d)
            if here is not None:
                rule += f": {value(here)} here"
            body.append(f"# {_key(k)} is unset ({rule})")
            continue
        if isinstance(v, dict) and any(isinstance(x, dict) for x in v.values()):
            subs.append((k, v))
        else:
            body.append(f"{_key(k)} = {value(v)}")
    if path and (body or not subs):
        lines.append("")
        lines.append("[" + ".".join(_key(p) for p in path) + "]")
    lines.extend(body)
    for k, v in subs:
        _table(lines, [*path, k], v, resolved)


def dumps(data: dict, resolved: dict | None = None) -> str:
    """``data`` (a dictionary of values and tables) as TOML text.

    Parameters
    ----------
    data : dict
        Top-level values first, then tables; nested tables of values become inline tables.
    resolved : dict, optional
        Dotted key -> the value an unset (``None``) setting takes in this scenario, written in
        its comment (:func:`imdrive.config.resolved.resolved_defaults`).

    Returns
    -------
    str
        TOML that :func:`tomllib.loads` reads back to ``data`` (without its ``None`` values).
    """
    lines: list[str] = []
    top = {k: v for k, v in data.items() if not isinstance(v, dict)}
    tables = {k: v for k, v in data.items() if isinstance(v, dict)}
    _table(lines, [], top, resolved or {})
    for k, v in tables.items():
        _table(lines, [k], v, resolved or {})
    return "\n".join(lines).lstrip("\n") + "\n"
