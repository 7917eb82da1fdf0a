"""Reading a sweep file's ``[axes]`` and ``[[heatmap]]`` tables into :class:`Axis` and
:class:`Heatmap` objects: grids, explicit values, random draws, named sets of overrides, and
the checks that name the offending key."""

from __future__ import annotations

import functools
import math
from dataclasses import fields, is_dataclass

import numpy as np

from imdrive.config.overrides import dotted, is_setting, key_path
from imdrive.config.pairs import pair_of
from imdrive.config.profiles import Profile
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.sweep.model import (
    AGGREGATES,
    CONVENIENCE,
    CONVENIENCE_TARGET,
    DEFAULT_MAX_RUNS,
    Axis,
    Heatmap,
    _number,
)


def _split(key: str) -> list[str]:
    return [p.strip() for p in key.split(".")]


def _flatten(table: dict, where: str, prefix: tuple[str, ...] = ()) -> list:
    """``[(parts, value)]`` of scenario overrides written as a (possibly nested) TOML table.

    Dotted keys (``compensator.enabled = true``) arrive nested; quoted ones
    (``"compensator.enabled" = true``) arrive as one key: both are accepted. A nested table is
    descended into while it names a table of the schema (a section such as ``compensator`` or
    ``plant.thermal``), so a profile table (``{initial, changes}``) is a value.
    """
    out = []
    for key, value in table.items():
        if "[" in key:  # one element of a profile: "control.speed_ref_rpm.changes[0].to"
            dotted_key = ".".join((*prefix, key.strip()))
            out.append((key_path(dotted_key, f"{where}.{dotted_key}"), value))
            continue
        parts = (*prefix, *_split(key))
        if not all(parts):
            raise ConfigError(f"{where}.{key}", "empty part in a key path")
        if isinstance(value, dict) and _is_table(parts):
            out.extend(_flatten(value, where, parts))
            continue
        if not is_setting(parts):
            raise ConfigError(
                f"{where}.{'.'.join(parts)}",
                "no such setting (see 'imdrive show PRESET' for the keys)",
            )
        out.append((parts, value))
    return out


@functools.cache
def _default_scenario() -> Scenario:
    return Scenario.from_dict({})


def _is_table(parts) -> bool:
    """Whether ``parts`` names a table of settings (``machine``, ``compensator``,
    ``plant.thermal``, ...) rather than a value, read from the shape of a default scenario: a
    profile, even when written as a table, is a value."""
    node = _default_scenario()
    for p in parts:
        if not _is_settings(node) or p not in {f.name for f in fields(node)}:
            return False
        node = getattr(node, p)
    return _is_settings(node)


def _is_settings(obj) -> bool:
    return is_dataclass(obj) and not isinstance(obj, type | Profile)


def _int(value, path: str, lo: int = 1) -> int:
    ok = isinstance(value, int) and not isinstance(value, bool)
    if not ok or value < lo:
        raise ConfigError(path, f"must be an integer >= {lo}, got {value!r}")
    return int(value)


def _axis_values(
    name: str, spec, random: bool, samples: int, rng, limit: int = DEFAULT_MAX_RUNS
) -> Axis:
    """Parse ``axes.NAME``; draws the samples of a random sweep.

    The spec forms, each parsed by its own function: a table of tables (a set axis,
    :func:`_set_axis`), a list or ``{values = [...]}`` (:func:`_listed_values`), and a range
    ``{min, max}`` with ``num`` or ``step`` in a grid sweep (:func:`_range_bounds`,
    :func:`_grid_points`). A random sweep draws from each: uniformly in a range, by an equally
    likely choice from a list or the sets.
    """
    where = f"axes.{name}"
    kind = _axis_kind(name, spec, where)
    if kind == "sets":
        return _set_axis(name, spec, where, random, samples, rng)
    path = key_path(name.replace(" ", ""), where) if kind == "path" else ()
    spec = _unwrap_values(spec, where)
    if isinstance(spec, list):
        values = _listed_values(spec, kind, where)
        if random:
            values = _draw(values, samples, rng)
        return Axis(name, kind, values, path=path, choice=random)
    lo, hi = _range_bounds(spec, where, random)
    if random:
        return Axis(name, kind, tuple(float(v) for v in rng.uniform(lo, hi, samples)), path=path)
    return Axis(name, kind, _grid_points(spec, lo, hi, where, limit), path=path)


def _axis_kind(name: str, spec, where: str) -> str:
    """``name`` for a convenience axis, ``"sets"`` for a table of tables, else ``"path"``."""
    if name in CONVENIENCE:
        return name
    if isinstance(spec, dict) and spec and all(isinstance(v, dict) for v in spec.values()):
        return "sets"
    key_path(name.replace(" ", ""), where)  # a setting, or one element of a profile
    return "path"


def _draw(values: tuple, samples: int, rng) -> tuple:
    """``samples`` equally likely choices from ``values`` (a random sweep's listed axis)."""
    return tuple(values[int(k)] for k in rng.integers(0, len(values), samples))


def _set_axis(name: str, spec: dict, where: str, random: bool, samples: int, rng) -> Axis:
    """A set axis: each entry of ``spec`` names a table of overrides."""
    sets = {label: tuple(_flatten(table, f"{where}.{label}")) for label, table in spec.items()}
    labels = tuple(sets)
    if random:
        labels = _draw(labels, samples, rng)
    return Axis(name, "sets", labels, sets, choice=random)


def _unwrap_values(spec, where: str):
    """The list of ``{values = [...]}`` (nothing else allowed beside it), else ``spec``."""
    if not (isinstance(spec, dict) and "values" in spec):
        return spec
    extra = set(spec) - {"values"}
    if extra:
        raise ConfigError(f"{where}.{sorted(extra)[0]}", "unknown key (with 'values')")
    return spec["values"]


def _listed_values(spec: list, kind: str, where: str) -> tuple:
    """Explicit values: at least one, all of one type; numbers for a convenience axis."""
    if not spec:
        raise ConfigError(where, "is empty: give at least one value")
    kinds = {
        type(v) if not isinstance(v, int | float) or isinstance(v, bool) else float for v in spec
    }
    if len(kinds) > 1:
        raise ConfigError(where, "values must all be numbers, all strings or all booleans")
    if kind in CONVENIENCE:
        for k, v in enumerate(spec):
            _number(v, f"{where}[{k}]")
    return tuple(spec)


def _range_bounds(spec, where: str, random: bool) -> tuple[float, float]:
    """Check a range ``{min, max, ...}`` (its keys, both ends, ``min <= max``): ``(min, max)``."""
    if not isinstance(spec, dict):
        if isinstance(spec, int | float) and not isinstance(spec, bool):
            raise ConfigError(where, "a single value is not an axis: write [value] or use [set]")
        raise ConfigError(where, "must be a list of values, {min, max, num|step} or override sets")
    if not spec:
        raise ConfigError(where, "is empty: give values, or {min, max, num} / {min, max, step}")
    allowed = {"min", "max"} if random else {"min", "max", "num", "step"}
    extra = set(spec) - allowed
    if extra:
        rule = "unknown key" if not random else "unknown key (a random sweep draws from min, max)"
        raise ConfigError(f"{where}.{sorted(extra)[0]}", rule)
    for k in ("min", "max"):
        if k not in spec:
            raise ConfigError(f"{where}.{k}", "is required")
    lo = _number(spec["min"], f"{where}.min")
    hi = _number(spec["max"], f"{where}.max")
    if lo > hi:
        raise ConfigError(f"{where}.min", f"must be <= max (min = {lo:g} > max = {hi:g})")
    return lo, hi


def _too_many(where: str, n: int, limit: int) -> ConfigError:
    return ConfigError(
        where,
        f"gives {n:.4g} points: the sweep would exceed its limit of runs (max_runs, "
        f"--max-runs; {limit:.4g} left for this axis)",
    )


def _grid_points(
    spec: dict, lo: float, hi: float, where: str, limit: int = DEFAULT_MAX_RUNS
) -> tuple[float, ...]:
    """The points of a grid range: ``num`` points, ends included, or ``lo, lo + step, ...``.

    The number of points is computed first: more than ``limit`` is refused before any is built.
    """
    if ("num" in spec) == ("step" in spec):
        raise ConfigError(where, "give exactly one of num or step with min and max")
    if "num" in spec:
        num = _int(spec["num"], f"{where}.num", lo=1)
        if num > limit:
            raise _too_many(f"{where}.num", num, limit)
        if num == 1 and lo != hi:
            raise ConfigError(f"{where}.num", "must be >= 2 when min < max")
        return (lo,) if num == 1 else tuple(float(v) for v in np.linspace(lo, hi, num))
    step = _number(spec["step"], f"{where}.step")
    if step <= 0:
        raise ConfigError(f"{where}.step", f"must be > 0 (got {step:g})")
    span = (hi - lo) / step * (1 + 1e-12) + 1e-9
    if not math.isfinite(span) or span >= 1_000_000:
        raise ConfigError(f"{where}.step", f"gives {span:.4g} points (more than 1e6)")
    n = int(math.floor(span)) + 1
    if n > limit:
        raise _too_many(f"{where}.step", n, limit)
    return tuple(lo + k * step for k in range(n))


def _heatmaps(items, axes: tuple[Axis, ...], random: bool) -> tuple[Heatmap, ...]:
    """The ``[[heatmap]]`` tables, checked against the axes and the metric columns."""
    if items is None:
        return _default_heatmaps(axes, random)
    if not isinstance(items, list):
        raise ConfigError("heatmap", "must be an array of tables: [[heatmap]]")
    return tuple(_heatmap(h, f"heatmap[{k}]", axes, random) for k, h in enumerate(items))


def _default_heatmaps(axes: tuple[Axis, ...], random: bool) -> tuple[Heatmap, ...]:
    """Without ``[[heatmap]]``: the speed error over the first two numeric axes, if any."""
    numeric = [a.name for a in axes if a.numeric]
    if len(numeric) < 2:
        return ()
    other = [a.name for a in axes if a.name not in numeric[:2]]
    cat = [a for a in other if not random or _categorical(axes, a)]
    return (Heatmap(numeric[0], numeric[1], "speed_error_rpm", cat[0] if cat else None),)


def _heatmap(h, where: str, axes: tuple[Axis, ...], random: bool) -> Heatmap:
    """One ``[[heatmap]]`` table."""
    from imdrive.run.batch import COLUMNS, metrics_dtypes

    if not isinstance(h, dict):
        raise ConfigError(where, "must be a table")
    extra = set(h) - {"x", "y", "value", "rows", "cols", "agg"}
    if extra:
        raise ConfigError(f"{where}.{sorted(extra)[0]}", "unknown key")
    names = [a.name for a in axes]
    for key in ("x", "y"):
        if h.get(key) not in names:
            raise ConfigError(f"{where}.{key}", f"must name an axis ({', '.join(names)})")
    for key in ("rows", "cols"):
        if key in h:
            _check_panel_axis(h[key], f"{where}.{key}", axes, random)
    kinds = metrics_dtypes()
    metric_cols = [c for c in COLUMNS if c != "drive" and kinds[c] != np.dtype(object)]
    value = h.get("value", "speed_error_rpm")
    if value not in metric_cols:
        raise ConfigError(f"{where}.value", f"must be a metric ({', '.join(metric_cols)})")
    agg = h.get("agg", "mean")
    if agg not in AGGREGATES:
        raise ConfigError(f"{where}.agg", f"must be one of {', '.join(AGGREGATES)}")
    return Heatmap(h["x"], h["y"], value, h.get("rows"), h.get("cols"), agg)


def _check_panel_axis(name, where: str, axes: tuple[Axis, ...], random: bool) -> None:
    """``rows``/``cols`` name an axis; in a random sweep one of few values (list or sets)."""
    names = [a.name for a in axes]
    if name not in names:
        raise ConfigError(where, f"must name an axis ({', '.join(names)})")
    if random and not _categorical(axes, name):
        raise ConfigError(where, "in a random sweep, only an axis of listed values or sets")


def _categorical(axes, name) -> bool:
    """Whether a random sweep's axis takes few values (drawn from a list or sets)."""
    return next(a for a in axes if a.name == name).choice


def _axes(
    spec, random: bool, samples: int, rng, max_runs: int = DEFAULT_MAX_RUNS
) -> tuple[Axis, ...]:
    """Every axis of ``[axes]``, in file order; no two may set the same scenario key.

    A grid's size (the product of the axes' lengths) is kept below ``max_runs`` axis by axis,
    each axis's length known before its points are built.
    """
    if not isinstance(spec, dict) or not spec:
        raise ConfigError("axes", "is required and needs at least one axis")
    axes_list: list[Axis] = []
    size = 1
    for n, s in spec.items():
        a = _axis_values(n, s, random, samples, rng, max(max_runs // size, 1))
        if not random:
            size *= len(a.values)
            if size > max_runs:
                raise ConfigError(
                    f"axes.{n}",
                    f"makes the grid {size:.4g} runs: more than the limit of {max_runs:.4g} "
                    "(--max-runs)",
                )
        axes_list.append(a)
    axes = tuple(axes_list)
    _check_disjoint(axes)
    _check_scalar(axes)
    return axes


def _check_scalar(axes: tuple[Axis, ...]) -> None:
    """Refuse an axis whose values are tables or lists (a profile, a measured table, a module
    list): such a value has no short label for the table and the figures; a set axis names
    each one."""
    for a in axes:
        if a.kind != "sets" and any(isinstance(v, list | dict) for v in a.values):
            raise ConfigError(
                f"axes.{a.name}",
                "values are tables or lists: sweep them as a set axis, one named table of "
                "overrides per value ([axes.NAME] a = { KEY = ... }, b = { KEY = ... })",
            )


def _axis_keys(a: Axis) -> set[tuple[str, ...]]:
    """The scenario keys axis ``a`` sets: its key path, a convenience axis's target, or every
    key any of a set axis's sets overrides."""
    if a.kind == "path":
        return {tuple(a.path)}
    if a.kind in CONVENIENCE:
        return {tuple(CONVENIENCE_TARGET[a.kind].split("."))}
    return {tuple(parts) for overrides in a.sets.values() for parts, _ in overrides}


def _overlap(k1: tuple[str, ...], k2: tuple[str, ...]) -> bool:
    """Whether two key paths set the same value: equal, or one a table holding the other."""
    n = min(len(k1), len(k2))
    return k1[:n] == k2[:n]


def _twins(k1: tuple[str, ...], k2: tuple[str, ...]) -> bool:
    """Whether two keys are the absolute and per-unit members of one pair
    (:data:`imdrive.config.pairs.PAIRS`): one quantity stated twice, so one would be cleared
    or win over the other."""
    pair = pair_of(dotted(k1))
    return pair is not None and dotted(k2) in pair.twins(dotted(k1))


def _check_disjoint(axes: tuple[Axis, ...]) -> None:
    """Refuse two axes that set the same key (a key-path or convenience axis and a set axis,
    two set axes, or a table and a key inside it), or the absolute and per-unit twins of one
    quantity (``estimator.R2_ohm`` and ``R2_ratio``): one value would silently win, and rows
    with different labels would be the same drive."""
    seen: list[tuple[Axis, set]] = []
    for a in axes:
        keys = _axis_keys(a)
        for b, other in seen:
            for k in sorted(keys):
                hit = next((o for o in sorted(other) if _overlap(k, o)), None)
                if hit is not None:
                    both = dotted(k) if k == hit else f"{dotted(k)} / {dotted(hit)}"
                    raise ConfigError(
                        f"axes.{a.name}",
                        f"sets {both}, as axis {b.name} does: two axes may not set the same key",
                    )
                twin = next((o for o in sorted(other) if _twins(k, o)), None)
                if twin is not None:
                    raise ConfigError(
                        f"axes.{a.name}",
                        f"sets {dotted(k)} / {dotted(twin)}, as axis {b.name} does: the "
                        "absolute and per-unit twins of one quantity; sweep one of them",
                    )
        seen.append((a, keys))
