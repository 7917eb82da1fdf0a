"""The sweep specification: reading, validating and expanding a sweep file.

A sweep file (format in :mod:`imdrive.sweep`) names a base scenario, overrides for every run and
axes; :func:`parse_sweep` turns it into a :class:`Sweep`, which knows the value of every axis of
every run (:meth:`Sweep.run_values`) and builds each run's scenario (:meth:`Sweep.scenario`).
Every run's scenario is built and validated when the sweep is read, so bad input raises
:class:`~imdrive.errors.ConfigError` naming the field before anything runs.

Notes
-----
A run's scenario goes through the same override mechanism as ``imdrive run --set``
(:func:`imdrive.config.overrides.set_path` on the base's TOML dictionary, then
:meth:`Scenario.from_dict <imdrive.config.scenario.Scenario.from_dict>`); only the convenience
axes ``R2_ratio``, ``R1_ratio``, ``speed_rpm`` and ``load_Nm`` then replace fields of the
validated scenario.
Pure Python on top of :mod:`imdrive.config`; only checking the metric names of ``[[heatmap]]``
tables loads the run layer (:data:`imdrive.run.batch.COLUMNS`).
"""

from __future__ import annotations

import copy
import functools
import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass, field, fields, is_dataclass, replace
from importlib import resources
from pathlib import Path

import numpy as np

from imdrive.config.overrides import is_setting, set_path
from imdrive.config.presets import scenario_text
from imdrive.config.profiles import Profile
from imdrive.config.scenario import Scenario
from imdrive.config.validation import check_name, slug
from imdrive.errors import ConfigError

CONVENIENCE = ("R2_ratio", "R1_ratio", "speed_rpm", "load_Nm")
CONVENIENCE_TARGET = {
    "R2_ratio": "estimator.R2_ohm",
    "R1_ratio": "estimator.R1_ohm",
    "speed_rpm": "control.speed_ref_rpm",
    "load_Nm": "load.torque_Nm",
}
TOP_KEYS = (
    "name",
    "description",
    "base",
    "window_s",
    "chunk_size",
    "samples",
    "seed",
    "set",
    "axes",
    "heatmap",
)
AGGREGATES = ("mean", "min", "max", "absmax")
DEFAULT_CHUNK = 32
#: Largest sweep accepted (runs), unless ``max_runs`` (``--max-runs``) says otherwise: the size
#: is computed from the axes before any value is built, so an absurd grid is refused at once.
DEFAULT_MAX_RUNS = 10_000_000
#: Distinct scenarios built when a sweep is read (every combination of the axes other than
#: ``speed_rpm`` and ``load_Nm``, which change nothing but a profile's last value). Beyond,
#: each axis value is validated alone and the combinations as they run.
VALIDATE_ALL_MAX = 20_000


# ------------------------------------------------------------------------------------------
# the sweep


@dataclass(frozen=True)
class Axis:
    """One axis: its name, kind and values.

    ``kind`` is ``"path"`` (a scenario key), one of :data:`CONVENIENCE`, or ``"sets"``. For a
    grid sweep ``values`` are the axis points; for a random sweep the drawn value of every run.
    For a set axis ``values`` are the set names and ``sets`` maps a name to its overrides.

    Attributes
    ----------
    name : str
        The axis name (a key path, a convenience axis or a set axis).
    kind : str
        ``"path"``, a name of :data:`CONVENIENCE`, or ``"sets"``.
    values : tuple
        The axis points (grid) or each run's drawn value (random), in the unit of the key or
        convenience axis (``speed_rpm`` in rpm, ``R2_ratio`` dimensionless); set names for a
        set axis.
    sets : dict
        Set name -> its overrides (set axes only).
    path : tuple of str
        The scenario key path (``kind == "path"``).
    choice : bool
        Random sweep: the value is drawn from listed values or sets.
    """

    name: str
    kind: str
    values: tuple
    sets: dict = field(default_factory=dict)
    path: tuple[str, ...] = ()
    choice: bool = False  # random sweep: drawn from listed values or sets

    @property
    def numeric(self) -> bool:
        """Whether every value is a number (the table column is then float)."""
        return self.kind != "sets" and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in self.values
        )

    def points(self) -> list:
        """Distinct values in order of first appearance.

        Returns
        -------
        list
            The distinct values, in the axis's unit.
        """
        return list(dict.fromkeys(self.values))


@dataclass(frozen=True)
class Heatmap:
    """One ``[[heatmap]]`` of a sweep file.

    Attributes
    ----------
    x, y : str
        The axes along x and y.
    value : str
        The metric column shown.
    rows, cols : str or None
        Axes giving one panel per value, down and across.
    agg : str
        How the other axes are aggregated: ``mean``, ``min``, ``max`` or ``absmax``.
    """

    x: str
    y: str
    value: str = "speed_error_rpm"
    rows: str | None = None
    cols: str | None = None
    agg: str = "mean"


@dataclass(frozen=True)
class Sweep:
    """A resolved sweep: base scenario, axes, number of runs. Picklable (sent to dask).

    Runs that share the values of the set and key-path axes share one validated scenario
    (kept, up to a bound, in ``_scenarios``); the convenience axes are applied to it per run.

    Attributes
    ----------
    name, description : str
        The sweep's name (default store ``out/sweep-NAME``) and free text.
    base : Scenario
        The base scenario, after ``[set]``.
    base_data : dict
        The same in TOML-shaped form: every run's overrides are set on a copy.
    axes : tuple of Axis
        The axes, in file order.
    random : bool
        A random sweep (``samples``) rather than a grid.
    n_runs : int
        Number of runs.
    seed : int
        Seed of a random sweep's generator.
    window_s : float
        Steady-state window of the metrics, s.
    chunk_size : int
        Runs per chunk of the store.
    heatmaps : tuple of Heatmap
        The figures.
    source : str
        The sweep file's text.
    validation : dict
        What reading the sweep checked, and the runs known to fail.
    """

    name: str
    description: str
    base: Scenario
    base_data: dict  # TOML-shaped base (after [set]): every run's overrides are set on a copy
    axes: tuple[Axis, ...]
    random: bool
    n_runs: int
    seed: int
    window_s: float
    chunk_size: int
    heatmaps: tuple[Heatmap, ...]
    source: str = ""
    #: what reading the sweep checked, and the runs known to fail (see :func:`_validate`)
    validation: dict = field(default_factory=dict, compare=False)
    # validated scenarios by value of the set and key-path axes (see _overridden)
    _scenarios: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    # -- runs ------------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, ...]:
        """Number of values of each axis."""
        return tuple(len(a.values) for a in self.axes)

    def run_values(self, i: int) -> tuple:
        """The value of every axis of run ``i``.

        Parameters
        ----------
        i : int
            Run index.

        Returns
        -------
        tuple
            One value per axis, in the axis's unit (the set name for a set axis).
        """
        if not 0 <= i < self.n_runs:
            raise IndexError(i)
        if self.random:
            return tuple(a.values[i] for a in self.axes)
        idx = np.unravel_index(i, self.shape)
        return tuple(a.values[int(j)] for a, j in zip(self.axes, idx, strict=True))

    def scenario(self, i: int) -> Scenario:
        """The scenario of run ``i``.

        Parameters
        ----------
        i : int
            Run index.

        Returns
        -------
        Scenario
            The validated scenario.
        """
        return self.scenario_for(self.run_values(i))

    def scenario_for(self, values: tuple) -> Scenario:
        """The scenario for given axis values.

        Parameters
        ----------
        values : tuple
            One value per axis, as :meth:`run_values` gives them.

        Returns
        -------
        Scenario
            The validated scenario.
        """
        return _build(self, dict(zip((a.name for a in self.axes), values, strict=True)))

    def n_chunks(self, chunk_size: int | None = None) -> int:
        """Number of chunks of the store.

        Parameters
        ----------
        chunk_size : int, optional
            Runs per chunk; default the sweep's.

        Returns
        -------
        int
            The number of chunks (the last may be short).
        """
        cs = chunk_size or self.chunk_size
        return (self.n_runs + cs - 1) // cs

    def chunk_runs(self, j: int, chunk_size: int | None = None) -> range:
        """The runs of chunk ``j``.

        Parameters
        ----------
        j : int
            Chunk index.
        chunk_size : int, optional
            Runs per chunk; default the sweep's.

        Returns
        -------
        range
            Run indices.
        """
        cs = chunk_size or self.chunk_size
        return range(j * cs, min((j + 1) * cs, self.n_runs))

    def fingerprint(self) -> str:
        """Hash of everything that determines the runs (not the chunking or the figures).

        Returns
        -------
        str
            20 hexadecimal digits.
        """
        spec = {
            "base": self.base.to_dict(),
            "axes": [
                {"name": a.name, "kind": a.kind, "values": list(a.values), "sets": a.sets}
                for a in self.axes
            ],
            "random": self.random,
            "n_runs": self.n_runs,
            "window_s": self.window_s,
        }
        text = json.dumps(spec, sort_keys=True, default=repr)
        return hashlib.sha256(text.encode()).hexdigest()[:20]

    def inputs(self, runs: range):
        """Table of run index and axis values.

        Parameters
        ----------
        runs : range
            Run indices.

        Returns
        -------
        pandas.DataFrame
            Column ``run`` and one column per axis.
        """
        import pandas as pd

        cols: dict = {"run": np.arange(runs.start, runs.stop, dtype=np.int64)}
        vals = [self.run_values(i) for i in runs]
        for k, a in enumerate(self.axes):
            col = [v[k] for v in vals]
            cols[a.name] = np.array(col, dtype=float) if a.numeric else col
        return pd.DataFrame(cols)


# ------------------------------------------------------------------------------------------
# building a run's scenario
#
# One override mechanism, shared with ``imdrive run --set`` (imdrive.config.overrides): the set
# axes' overrides, then the key-path axes, are set on a copy of the base's TOML dictionary,
# which Scenario.from_dict validates once. Runs that differ only in convenience axes share that
# scenario (cached on the sweep), and the convenience axes replace single fields of it.

_CACHE_MAX = 1024  # validated scenarios kept per sweep (distinct set / key-path values)


def _apply(sc: Scenario, parts: tuple[str, ...], value) -> Scenario:
    """Scenario ``sc`` with the key ``parts`` set, as ``Scenario.read`` with that override.

    Goes through :func:`~imdrive.config.overrides.set_path` on ``sc.to_dict()``. A new
    ``machine.preset`` replaces every machine parameter with the preset's.
    """
    data = sc.to_dict()
    if tuple(parts) == ("machine", "preset"):
        data["machine"] = {}
    set_path(data, parts, value)
    return Scenario.from_dict(data)


def _with_final(profile: Profile, value: float) -> Profile:
    """``profile`` with the value of its last breakpoint set to ``value``."""
    pts = list(profile.points)
    pts[-1] = (pts[-1][0], float(value))
    return Profile(tuple(pts))


def _with_R2_ratio(sc: Scenario, ratio: float) -> Scenario:
    return replace(sc, estimator=replace(sc.estimator, R2_ohm=ratio * sc.machine.R2_ohm))


def _with_R1_ratio(sc: Scenario, ratio: float) -> Scenario:
    return replace(sc, estimator=replace(sc.estimator, R1_ohm=ratio * sc.machine.R1_ohm))


def _with_speed(sc: Scenario, rpm: float) -> Scenario:
    profile = _with_final(sc.control.speed_ref_rpm, rpm)
    return replace(sc, control=replace(sc.control, speed_ref_rpm=profile))


def _with_load(sc: Scenario, torque: float) -> Scenario:
    return replace(sc, load=replace(sc.load, torque_Nm=_with_final(sc.load.torque_Nm, torque)))


# the convenience axes, applied in this order after the overrides
CONVENIENCE_APPLY = {
    "R2_ratio": _with_R2_ratio,
    "R1_ratio": _with_R1_ratio,
    "speed_rpm": _with_speed,
    "load_Nm": _with_load,
}


def _number(value, path: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(path, f"must be a finite number, got {value!r}")
    return float(value)


def _build(sweep: Sweep, point: dict) -> Scenario:
    """The scenario of one point (axis name -> value) of ``sweep``."""
    sc = _overridden(sweep, point)
    for kind, apply in CONVENIENCE_APPLY.items():
        for a in sweep.axes:
            if a.kind == kind:
                sc = apply(sc, _number(point[a.name], f"axes.{a.name}"))
    return sc


def _overridden(sweep: Sweep, point: dict) -> Scenario:
    """The base with the set axes' overrides, then the key-path axes, of ``point`` (cached)."""
    axes = [a for a in sweep.axes if a.kind in ("sets", "path")]
    key = tuple(repr(point[a.name]) for a in axes)
    sc = sweep._scenarios.get(key)
    if sc is None:
        data = copy.deepcopy(sweep.base_data)
        for a in axes:
            if a.kind == "sets":
                for parts, value in a.sets[point[a.name]]:
                    set_path(data, parts, value)
        for a in axes:
            if a.kind == "path":
                set_path(data, a.path, point[a.name])
        sc = Scenario.from_dict(data)
        if len(sweep._scenarios) >= _CACHE_MAX:
            sweep._scenarios.clear()
        sweep._scenarios[key] = sc
    return sc


# ------------------------------------------------------------------------------------------
# reading a sweep file


def sweep_names() -> list[str]:
    """Names of the built-in sweeps.

    Returns
    -------
    list of str
        Sorted names.
    """
    root = resources.files("imdrive.sweep").joinpath("presets")
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def sweep_text(ref: str) -> tuple[str, Path | None]:
    """Text of a built-in sweep by name, or of the file at that path.

    Parameters
    ----------
    ref : str
        A name of :func:`sweep_names` or a path.

    Returns
    -------
    text : str
        The TOML text.
    folder : pathlib.Path or None
        The file's folder (where relative paths start); None for a built-in sweep.
    """
    if ref in sweep_names():
        return resources.files("imdrive.sweep").joinpath(f"presets/{ref}.toml").read_text(), None
    p = Path(ref)
    if p.is_file():
        try:
            return p.read_text(encoding="utf-8-sig"), p.resolve().parent
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigError("sweep", f"cannot read {p}: {exc}") from None
    raise ConfigError(
        "sweep", f"{ref!r} is neither a built-in sweep ({', '.join(sweep_names())}) nor a file"
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
    path = tuple(_split(name)) if kind == "path" else ()
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
    parts = _split(name)
    if not is_setting(parts):
        raise ConfigError(where, "no such setting (see 'imdrive show PRESET' for the keys)")
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
    from imdrive.run.batch import COLUMNS

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
    metric_cols = [c for c in COLUMNS if c != "drive"]
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


def parse_sweep(
    text: str,
    folder: Path | None = None,
    default_name: str = "sweep",
    max_runs: int = DEFAULT_MAX_RUNS,
) -> Sweep:
    """Read and validate a sweep from its TOML text.

    The size is computed from the axes before any value is built and refused above
    ``max_runs``. Every run's scenario is validated here, derived quantities included
    (:func:`_validate`), so a sweep that parses runs; a run whose derived parameters cannot be
    computed is listed in :attr:`Sweep.validation` and recorded as failed when it runs.

    Parameters
    ----------
    text : str
        The sweep file's text.
    folder : pathlib.Path, optional
        Where relative paths in it start.
    default_name : str
        Name when the file gives none.
    max_runs : int
        Refuse a sweep of more runs.

    Returns
    -------
    Sweep
        The resolved, validated sweep.
    """
    max_runs = _int(max_runs, "--max-runs")
    data = _read_toml(text)
    name, desc = _name_and_description(data, default_name)
    base_data = _base_data(data, folder)
    base = Scenario.from_dict(base_data)
    window_s = _number(data.get("window_s", 0.5), "window_s")
    if window_s < 0:
        raise ConfigError("window_s", f"must be >= 0 (got {window_s:g})")
    chunk_size = _int(data.get("chunk_size", DEFAULT_CHUNK), "chunk_size")
    random, samples, seed = _sampling(data, max_runs)
    axes = _axes(data.get("axes"), random, samples, np.random.default_rng(seed), max_runs)
    sweep = Sweep(
        name=name,
        description=desc,
        base=base,
        base_data=base_data,
        axes=axes,
        random=random,
        n_runs=samples if random else math.prod(len(a.values) for a in axes),
        seed=seed,
        window_s=window_s,
        chunk_size=chunk_size,
        heatmaps=_heatmaps(data.get("heatmap"), axes, random),
        source=text,
    )
    return replace(sweep, validation=_validate(sweep))


def _read_toml(text: str) -> dict:
    """The sweep file as a dictionary, with only known top-level keys."""
    try:
        data = tomllib.loads(text.removeprefix("\ufeff"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError("sweep", f"invalid TOML: {exc}") from None
    for key in data:
        if key not in TOP_KEYS:
            raise ConfigError(key, f"unknown key (a sweep file has {', '.join(TOP_KEYS)})")
    return data


def _name_and_description(data: dict, default_name: str) -> tuple[str, str]:
    name = data.get("name", default_name)
    desc = data.get("description", "")
    for key, v in (("name", name), ("description", desc)):
        if not isinstance(v, str):
            raise ConfigError(key, "must be a string")
    try:
        check_name(name)
    except ConfigError as exc:
        raise ConfigError("name", exc.rule) from None
    return name, desc


def _base_data(data: dict, folder: Path | None) -> dict:
    """The base scenario's TOML dictionary with the ``[set]`` overrides applied."""
    if "base" not in data:
        raise ConfigError("base", "is required: a scenario preset name or a scenario file")
    base_ref = data["base"]
    if not isinstance(base_ref, str):
        raise ConfigError("base", "must be a string")
    if folder is not None and not Path(base_ref).is_absolute() and (folder / base_ref).is_file():
        base_ref = str(folder / base_ref)
    try:
        base_data = tomllib.loads(scenario_text(base_ref).removeprefix("\ufeff"))
    except ConfigError as exc:
        raise ConfigError("base", exc.rule) from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError("base", f"invalid TOML in {base_ref}: {exc}") from None
    sets = data.get("set", {})
    if not isinstance(sets, dict):
        raise ConfigError("set", "must be a table of scenario keys")
    for parts, value in _flatten(sets, "set"):
        set_path(base_data, parts, value)
    return base_data


def _sampling(data: dict, max_runs: int = DEFAULT_MAX_RUNS) -> tuple[bool, int, int]:
    """``(random, samples, seed)``: a random sweep has ``samples``; only it has a ``seed``."""
    random = "samples" in data
    samples = _int(data["samples"], "samples") if random else 0
    if samples > max_runs:
        raise ConfigError(
            "samples", f"{samples:.4g} runs: more than the limit of {max_runs:.4g} (--max-runs)"
        )
    seed = _int(data.get("seed", 0), "seed", lo=0)
    if "seed" in data and not random:
        raise ConfigError("seed", "only for a random sweep (with samples = N)")
    return random, samples, seed


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
    targets: dict[str, str] = {}
    for a in axes:
        if a.kind == "path":
            key = ".".join(a.path)
        elif a.kind in CONVENIENCE:
            key = CONVENIENCE_TARGET[a.kind]
        else:
            continue
        if key in targets:
            raise ConfigError(f"axes.{a.name}", f"sets {key}, as axis {targets[key]} does")
        targets[key] = a.name
    return axes


def _validate(sweep: Sweep) -> dict:
    """Validate every run before anything runs; return what was checked and what will fail.

    First each axis value alone on the base (an error names the axis), then every distinct
    combination of the axes other than ``speed_rpm`` and ``load_Nm`` (these change only a
    profile's last value, checked finite when read), at most :data:`VALIDATE_ALL_MAX` of them:
    a combination a scenario rule refuses raises :class:`~imdrive.errors.ConfigError` naming
    the run. Each scenario's arrays are built too (:func:`imdrive.run.build.build_arrays`):
    one whose derived quantities overflow is not refused but listed (``failing``), since its
    row will be recorded as failed while the others run.

    Returns
    -------
    dict
        ``complete`` (every combination checked), ``checked`` (scenarios built),
        ``failing`` (``[(axis values, message)]`` of the combinations that will fail, first 20),
        ``n_failing`` (their number).
    """
    from imdrive.run.build import build_arrays

    failing: list = []
    n_failing = 0

    def derived(sc: Scenario, label: str) -> None:
        nonlocal n_failing
        try:
            build_arrays(sc)
        except ConfigError as exc:
            n_failing += 1
            if len(failing) < 20:
                failing.append((label, str(exc)))

    checked = 0
    for a in sweep.axes:
        for v in a.points():
            try:
                sc = _build_one_axis(sweep, a, v)
            except ConfigError as exc:
                raise ConfigError(f"axes.{a.name}", f"value {v!r} is rejected: {exc}") from None
            checked += 1
            if a.kind not in ("speed_rpm", "load_Nm"):
                derived(sc, f"{a.name} = {v!r}")
    joint = [k for k, a in enumerate(sweep.axes) if a.kind not in ("speed_rpm", "load_Nm")]
    combos = _combinations(sweep, joint)
    complete = combos is not None
    if combos is not None and len(joint) > 1:
        failing.clear()
        n_failing = 0
        first = tuple(a.values[0] for a in sweep.axes)
        for combo in combos:
            values = list(first)
            for k, v in zip(joint, combo, strict=True):
                values[k] = v
            pt = ", ".join(f"{sweep.axes[k].name} = {values[k]!r}" for k in joint)
            try:
                sc = sweep.scenario_for(tuple(values))
            except ConfigError as exc:
                raise ConfigError(f"axes ({pt})", str(exc)) from None
            checked += 1
            derived(sc, pt)
    return {"complete": complete, "checked": checked, "failing": failing, "n_failing": n_failing}


def _combinations(sweep: Sweep, joint: list[int]):
    """The distinct value tuples of the axes ``joint`` over the runs, or None if too many."""
    if sweep.random:
        seen = dict.fromkeys(
            zip(*(sweep.axes[k].values for k in joint), strict=True) if joint else ()
        )
        return list(seen) if len(seen) <= VALIDATE_ALL_MAX else None
    points = [sweep.axes[k].points() for k in joint]
    if math.prod(len(p) for p in points) > VALIDATE_ALL_MAX:
        return None
    return list(itertools.product(*points))


def _build_one_axis(sweep: Sweep, axis: Axis, value) -> Scenario:
    single = replace(sweep, axes=(replace(axis, values=(value,)),), random=False, n_runs=1)
    return single.scenario(0)


def load_sweep(ref: str, max_runs: int | None = None) -> Sweep:
    """A built-in sweep by name, or a sweep file by path.

    Parameters
    ----------
    ref : str
        A name of :func:`sweep_names` or a path.
    max_runs : int, optional
        Refuse a sweep of more runs (default :data:`DEFAULT_MAX_RUNS`).

    Returns
    -------
    Sweep
        The resolved, validated sweep.
    """
    text, folder = sweep_text(ref)
    default = ref if folder is None else slug(Path(ref).stem)
    return parse_sweep(text, folder, default, DEFAULT_MAX_RUNS if max_runs is None else max_runs)
