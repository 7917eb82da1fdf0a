"""Parameter sweeps: many runs of one base scenario, on this machine or on a dask cluster.

``imdrive sweep SWEEP --out STORE`` reads a sweep file (or a built-in sweep by name, e.g.
``detuning-map``), runs every point with the batch engine (:mod:`imdrive.batch`) and writes a
tidy Parquet table, one row per run: the run index, the value of every axis and the summary
metrics of :mod:`imdrive.batch` (speed error, estimate error, ripple, R2 estimate and its error,
convergence time, peak current, divergence), plus heatmap figures.

Sweep file (TOML)
-----------------
::

    name = "my-sweep"                  # optional (default: the file name)
    description = "..."                # optional
    base = "sensorless"                # a scenario preset, or a scenario file (a relative path
                                       #   is taken from the sweep file's folder)
    window_s = 0.5                     # steady-state window of the metrics, s (default 0.5)
    chunk_size = 32                    # runs per chunk of the store (default 32; --chunk-size)
    samples = 200                      # only for a random sweep: number of runs ...
    seed = 1                           # ... and the seed of the generator (default 0)

    [set]                              # overrides of the base for every run (optional)
    simulation.t_end_s = 6             # dotted keys, as in a scenario file
    simulation.log_every = 10

    [axes]                             # one entry per axis, in this order (at least one)
    R2_ratio = { min = 0.6, max = 1.4, num = 9 }       # grid: num points, ends included
    speed_rpm = { min = 100, max = 1500, step = 200 }  # grid: min, min + step, ... <= max
    load_Nm = [0, 6, 12]                               # explicit values
    "mras.bandwidth_Hz" = { values = [20, 40] }        # explicit values, other spelling
    [axes.variant]                                     # named sets of overrides
    plain = {}
    paper = { compensator.enabled = true, compensator.input = "e_d0" }

    [[heatmap]]                        # figures (optional; a default is drawn without them)
    x = "R2_ratio"                     # two axes ...
    y = "speed_rpm"
    value = "speed_error_rpm"          # ... and a metric column
    rows = "variant"                   # optional: one panel per value of an axis (rows) ...
    cols = "load_Nm"                   # ... and of another (columns)
    agg = "mean"                       # over the remaining axes: mean | min | max | absmax

Axes
    A *grid* sweep (no ``samples``) runs the Cartesian product of the axes, the last axis
    varying fastest; run ``i`` is the ``i``-th point of that product. A *random* sweep
    (``samples = N``) draws N points: ``{min, max}`` uniformly, a list or a set of overrides
    by an equally likely choice, each axis in file order from ``numpy.random.default_rng(seed)``.
    An axis is named by a scenario key path (``estimator.R2_ohm``, ``control.current_kp``,
    ``machine.J_kgm2``, ...; values as in a scenario file) or is one of

    * ``R2_ratio``  — R2_hat/R2: sets ``estimator.R2_ohm`` to the value times the run's
      ``machine.R2_ohm``;
    * ``speed_rpm`` — the final speed reference: sets the value of the last breakpoint of
      ``control.speed_ref_rpm`` (the base's ramp or step then ends at this speed);
    * ``load_Nm``   — the final load: the same for ``load.torque_Nm``;
    * any name whose value is a table of tables — a set axis: each entry names a set of
      overrides (``{}`` for none), its name is what the table records.

    For each run, a set axis's overrides are applied first, then the key-path axes, then
    ``R2_ratio``, ``speed_rpm``, ``load_Nm``. Two axes may not set the same key.

Bad input (an unknown key or parameter, an empty axis, ``min > max``, a value a scenario
rejects) raises :class:`~imdrive.errors.ConfigError` naming the field before anything runs:
every run's scenario is built and validated first. A run that diverges is recorded
(``diverged = True``, ``status``, ``diverged_at_s``; window metrics NaN) and the others go on.

Store
-----
``STORE/chunks/chunk-NNNNNN.parquet`` holds runs ``[N*chunk_size, (N+1)*chunk_size)``; each is
written to a temporary name and renamed into place (atomic), then ``STORE/manifest.json``
(sweep name, fingerprint of the resolved sweep, number of runs, chunk size, completed chunks) is
rewritten the same way. ``--resume`` runs only the chunks whose file is missing, so an
interrupted sweep loses at most the chunks in progress and duplicates nothing; without it, a
non-empty STORE is an error. At the end the chunks are read back, sorted by run and written as
``STORE/runs.parquet``; the figures go to ``STORE/figures/``. A run's results do not depend on
which chunk, process or machine computed it, so a resumed or distributed sweep gives the same
table as a local, uninterrupted one.

Execution: locally (default) each chunk is one call of the batch engine over all cores. With
``--scheduler ADDRESS`` (needs ``pip install 'imdrive[dask]'``) every chunk is a task on that
dask.distributed cluster (``Client(ADDRESS)``), run on one worker thread without the GIL; the
workers return the chunk's table and this process writes the store.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import os
import sys
import time
import tomllib
import typing
import uuid
from dataclasses import dataclass, field, is_dataclass, replace
from importlib import resources
from pathlib import Path

import numpy as np

from imdrive.config.overrides import _schema_allows
from imdrive.config.presets import scenario_text
from imdrive.config.profiles import Profile
from imdrive.config.scenario import SECTIONS, Scenario, _convert
from imdrive.errors import ConfigError

CONVENIENCE = ("R2_ratio", "speed_rpm", "load_Nm")
CONVENIENCE_TARGET = {
    "R2_ratio": "estimator.R2_ohm",
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
SIGNED_METRICS = ("speed_error_rpm", "speed_est_error_rpm", "R2_error_pct")


# ------------------------------------------------------------------------------------------
# the sweep


@dataclass(frozen=True)
class Axis:
    """One axis: its name, kind and values.

    ``kind`` is ``"path"`` (a scenario key), one of :data:`CONVENIENCE`, or ``"sets"``. For a
    grid sweep ``values`` are the axis points; for a random sweep the drawn value of every run.
    For a set axis ``values`` are the set names and ``sets`` maps a name to its overrides.
    """

    name: str
    kind: str
    values: tuple
    sets: dict = field(default_factory=dict)
    path: tuple[str, ...] = ()
    choice: bool = False  # random sweep: drawn from listed values or sets

    @property
    def numeric(self) -> bool:
        return self.kind != "sets" and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in self.values
        )

    def points(self) -> list:
        """Distinct values in order of first appearance."""
        return list(dict.fromkeys(self.values))


@dataclass(frozen=True)
class Heatmap:
    x: str
    y: str
    value: str = "speed_error_rpm"
    rows: str | None = None
    cols: str | None = None
    agg: str = "mean"


@dataclass(frozen=True)
class Sweep:
    """A resolved sweep: base scenario, axes, number of runs. Picklable (sent to dask)."""

    name: str
    description: str
    base: Scenario
    base_data: dict  # TOML-shaped base (after [set]), to rebuild on a machine.preset change
    axes: tuple[Axis, ...]
    random: bool
    n_runs: int
    seed: int
    window_s: float
    chunk_size: int
    heatmaps: tuple[Heatmap, ...]
    source: str = ""

    # -- runs ------------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a.values) for a in self.axes)

    def run_values(self, i: int) -> tuple:
        """The value of every axis (set name for a set axis) of run ``i``."""
        if not 0 <= i < self.n_runs:
            raise IndexError(i)
        if self.random:
            return tuple(a.values[i] for a in self.axes)
        idx = np.unravel_index(i, self.shape)
        return tuple(a.values[int(j)] for a, j in zip(self.axes, idx, strict=True))

    def scenario(self, i: int) -> Scenario:
        """The scenario of run ``i``."""
        return self.scenario_for(self.run_values(i))

    def scenario_for(self, values: tuple) -> Scenario:
        return _build(self, dict(zip((a.name for a in self.axes), values, strict=True)))

    def n_chunks(self, chunk_size: int | None = None) -> int:
        cs = chunk_size or self.chunk_size
        return (self.n_runs + cs - 1) // cs

    def chunk_runs(self, j: int, chunk_size: int | None = None) -> range:
        cs = chunk_size or self.chunk_size
        return range(j * cs, min((j + 1) * cs, self.n_runs))

    def fingerprint(self) -> str:
        """Hash of everything that determines the runs (not the chunking or the figures)."""
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
        """Table of run index and axis values for ``runs``."""
        import pandas as pd

        cols: dict = {"run": np.arange(runs.start, runs.stop, dtype=np.int64)}
        vals = [self.run_values(i) for i in runs]
        for k, a in enumerate(self.axes):
            col = [v[k] for v in vals]
            cols[a.name] = np.array(col, dtype=float) if a.numeric else col
        return pd.DataFrame(cols)


# ------------------------------------------------------------------------------------------
# building a run's scenario


_HINTS: dict[type, dict] = {}


def _hints(cls) -> dict:
    if cls not in _HINTS:
        _HINTS[cls] = typing.get_type_hints(cls)
    return _HINTS[cls]


def _set_field(obj, parts: tuple[str, ...], value, path: str):
    """``obj`` (a frozen dataclass) with the field at ``parts`` set to ``value`` (validated)."""
    name = parts[0]
    if len(parts) == 1:
        return replace(obj, **{name: _convert(_hints(type(obj))[name], value, path)})
    return replace(obj, **{name: _set_field(getattr(obj, name), parts[1:], value, path)})


def _apply(sc: Scenario, parts: tuple[str, ...], value) -> Scenario:
    """Scenario ``sc`` with the key ``parts`` set, as ``Scenario.read`` with that override."""
    path = ".".join(parts)
    if len(parts) == 1:  # name, description
        if not isinstance(value, str):
            raise ConfigError(path, "must be a string")
        return replace(sc, **{parts[0]: value})
    if parts[0] == "machine":
        v = _convert(_hints(type(sc.machine))[parts[1]], value, path)
        return replace(sc, machine=replace(sc.machine, **{parts[1]: v}))
    return _set_field(sc, parts, value, path)


def _with_final(profile: Profile, value: float) -> Profile:
    """``profile`` with the value of its last breakpoint set to ``value``."""
    pts = list(profile.points)
    pts[-1] = (pts[-1][0], float(value))
    return Profile(tuple(pts))


def _number(value, path: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(path, f"must be a finite number, got {value!r}")
    return float(value)


def _build(sweep: Sweep, point: dict) -> Scenario:
    """The scenario of one point (axis name -> value) of ``sweep``."""
    overrides: list[tuple[tuple[str, ...], object]] = []
    for a in sweep.axes:
        if a.kind == "sets":
            overrides.extend(a.sets[point[a.name]])
    for a in sweep.axes:
        if a.kind == "path":
            overrides.append((a.path, point[a.name]))
    preset = [v for p, v in overrides if p == ("machine", "preset")]
    sc = sweep.base
    if preset:
        data = copy.deepcopy(sweep.base_data)
        data.setdefault("machine", {})["preset"] = preset[-1]
        sc = Scenario.from_dict(data)
    for parts, value in overrides:
        if parts != ("machine", "preset"):
            sc = _apply(sc, parts, value)
    for a in sweep.axes:
        if a.kind == "R2_ratio":
            r = _number(point[a.name], f"axes.{a.name}")
            sc = _apply(sc, ("estimator", "R2_ohm"), r * sc.machine.R2_ohm)
        elif a.kind == "speed_rpm":
            v = _number(point[a.name], f"axes.{a.name}")
            sc = replace(
                sc,
                control=replace(sc.control, speed_ref_rpm=_with_final(sc.control.speed_ref_rpm, v)),
            )
        elif a.kind == "load_Nm":
            v = _number(point[a.name], f"axes.{a.name}")
            sc = replace(sc, load=replace(sc.load, torque_Nm=_with_final(sc.load.torque_Nm, v)))
    return sc


# ------------------------------------------------------------------------------------------
# reading a sweep file


def sweep_names() -> list[str]:
    """Names of the built-in sweeps."""
    root = resources.files("imdrive.sweep").joinpath("presets")
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def sweep_text(ref: str) -> tuple[str, Path | None]:
    """Text of a built-in sweep by name, or of the file at that path (and its folder)."""
    if ref in sweep_names():
        return resources.files("imdrive.sweep").joinpath(f"presets/{ref}.toml").read_text(), None
    p = Path(ref)
    if p.is_file():
        try:
            return p.read_text(encoding="utf-8"), p.resolve().parent
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
        if isinstance(value, dict) and _is_section_path(parts):
            out.extend(_flatten(value, where, parts))
            continue
        if not _schema_allows(list(parts)):
            raise ConfigError(
                f"{where}.{'.'.join(parts)}",
                "no such setting (see 'imdrive show PRESET' for the keys)",
            )
        out.append((parts, value))
    return out


def _is_section_path(parts) -> bool:
    """Whether ``parts`` names a table of the schema (a section or a nested settings table)."""
    if len(parts) == 1:
        return parts[0] in SECTIONS or parts[0] == "machine"
    cls = SECTIONS.get(parts[0])
    for p in parts[1:]:
        if cls is None or p not in _hints(cls):
            return False
        cls = _hints(cls)[p]
    return isinstance(cls, type) and is_dataclass(cls) and cls is not Profile


def _set_data(data: dict, parts, value) -> None:
    node = data
    for p in parts[:-1]:
        nxt = node.setdefault(p, {})
        if not isinstance(nxt, dict):
            raise ConfigError(".".join(parts), f"{p} is not a table")
        node = nxt
    node[parts[-1]] = value


def _int(value, path: str, lo: int = 1) -> int:
    ok = isinstance(value, int) and not isinstance(value, bool)
    if not ok or value < lo:
        raise ConfigError(path, f"must be an integer >= {lo}, got {value!r}")
    return int(value)


def _axis_values(name: str, spec, random: bool, samples: int, rng) -> Axis:
    """Parse ``axes.NAME``; draws the samples of a random sweep."""
    where = f"axes.{name}"
    parts = tuple(_split(name))
    if name in CONVENIENCE:
        kind = name
    elif isinstance(spec, dict) and spec and all(isinstance(v, dict) for v in spec.values()):
        kind = "sets"
    else:
        if not all(parts) or not _schema_allows(list(parts)):
            raise ConfigError(where, "no such setting (see 'imdrive show PRESET' for the keys)")
        kind = "path"
    if kind == "sets":
        sets = {}
        for label, table in spec.items():
            sets[label] = tuple(_flatten(table, f"{where}.{label}"))
        labels = tuple(sets)
        if random:
            labels = tuple(labels[int(k)] for k in rng.integers(0, len(labels), samples))
        return Axis(name, "sets", labels, sets, choice=random)
    if isinstance(spec, dict) and "values" in spec:
        extra = set(spec) - {"values"}
        if extra:
            raise ConfigError(f"{where}.{sorted(extra)[0]}", "unknown key (with 'values')")
        spec = spec["values"]
    if isinstance(spec, list):
        if not spec:
            raise ConfigError(where, "is empty: give at least one value")
        kinds = {
            type(v) if not isinstance(v, int | float) or isinstance(v, bool) else float
            for v in spec
        }
        if len(kinds) > 1:
            raise ConfigError(where, "values must all be numbers, all strings or all booleans")
        values = tuple(spec)
        if kind in CONVENIENCE:
            for k, v in enumerate(values):
                _number(v, f"{where}[{k}]")
        if random:
            values = tuple(values[int(k)] for k in rng.integers(0, len(values), samples))
        return Axis(name, kind, values, path=parts if kind == "path" else (), choice=random)
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
    if random:
        values = tuple(float(v) for v in rng.uniform(lo, hi, samples))
        return Axis(name, kind, values, path=parts if kind == "path" else ())
    if ("num" in spec) == ("step" in spec):
        raise ConfigError(where, "give exactly one of num or step with min and max")
    if "num" in spec:
        num = _int(spec["num"], f"{where}.num", lo=1)
        if num == 1 and lo != hi:
            raise ConfigError(f"{where}.num", "must be >= 2 when min < max")
        pts = [lo] if num == 1 else [float(v) for v in np.linspace(lo, hi, num)]
    else:
        step = _number(spec["step"], f"{where}.step")
        if step <= 0:
            raise ConfigError(f"{where}.step", f"must be > 0 (got {step:g})")
        n = int(math.floor((hi - lo) / step * (1 + 1e-12) + 1e-9)) + 1
        if n > 1_000_000:
            raise ConfigError(f"{where}.step", f"gives {n} points (more than 1e6)")
        pts = [lo + k * step for k in range(n)]
    return Axis(name, kind, tuple(pts), path=parts if kind == "path" else ())


def _heatmaps(items, axes: tuple[Axis, ...], random: bool) -> tuple[Heatmap, ...]:
    from imdrive.run.batch import COLUMNS

    names = [a.name for a in axes]
    metric_cols = [c for c in COLUMNS if c != "drive"]
    if items is None:
        numeric = [a.name for a in axes if a.numeric]
        if len(numeric) < 2:
            return ()
        other = [a.name for a in axes if a.name not in numeric[:2]]
        cat = [a for a in other if not random or _categorical(axes, a)]
        return (Heatmap(numeric[0], numeric[1], "speed_error_rpm", cat[0] if cat else None),)
    if not isinstance(items, list):
        raise ConfigError("heatmap", "must be an array of tables: [[heatmap]]")
    out = []
    for k, h in enumerate(items):
        where = f"heatmap[{k}]"
        if not isinstance(h, dict):
            raise ConfigError(where, "must be a table")
        extra = set(h) - {"x", "y", "value", "rows", "cols", "agg"}
        if extra:
            raise ConfigError(f"{where}.{sorted(extra)[0]}", "unknown key")
        for key in ("x", "y"):
            if h.get(key) not in names:
                raise ConfigError(f"{where}.{key}", f"must name an axis ({', '.join(names)})")
        for key in ("rows", "cols"):
            if key in h:
                if h[key] not in names:
                    raise ConfigError(f"{where}.{key}", f"must name an axis ({', '.join(names)})")
                if random and not _categorical(axes, h[key]):
                    raise ConfigError(
                        f"{where}.{key}", "in a random sweep, only an axis of listed values or sets"
                    )
        value = h.get("value", "speed_error_rpm")
        if value not in metric_cols:
            raise ConfigError(f"{where}.value", f"must be a metric ({', '.join(metric_cols)})")
        agg = h.get("agg", "mean")
        if agg not in AGGREGATES:
            raise ConfigError(f"{where}.agg", f"must be one of {', '.join(AGGREGATES)}")
        out.append(Heatmap(h["x"], h["y"], value, h.get("rows"), h.get("cols"), agg))
    return tuple(out)


def _categorical(axes, name) -> bool:
    """Whether a random sweep's axis takes few values (drawn from a list or sets)."""
    return next(a for a in axes if a.name == name).choice


def parse_sweep(text: str, folder: Path | None = None, default_name: str = "sweep") -> Sweep:
    """Read and validate a sweep from its TOML text (``folder``: where relative paths start)."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError("sweep", f"invalid TOML: {exc}") from None
    for key in data:
        if key not in TOP_KEYS:
            raise ConfigError(key, f"unknown key (a sweep file has {', '.join(TOP_KEYS)})")
    name = data.get("name", default_name)
    desc = data.get("description", "")
    for key, v in (("name", name), ("description", desc)):
        if not isinstance(v, str):
            raise ConfigError(key, "must be a string")
    if "base" not in data:
        raise ConfigError("base", "is required: a scenario preset name or a scenario file")
    base_ref = data["base"]
    if not isinstance(base_ref, str):
        raise ConfigError("base", "must be a string")
    if folder is not None and not Path(base_ref).is_absolute() and (folder / base_ref).is_file():
        base_ref = str(folder / base_ref)
    try:
        base_data = tomllib.loads(scenario_text(base_ref))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError("base", f"invalid TOML in {base_ref}: {exc}") from None
    sets = data.get("set", {})
    if not isinstance(sets, dict):
        raise ConfigError("set", "must be a table of scenario keys")
    for parts, value in _flatten(sets, "set"):
        _set_data(base_data, parts, value)
    base = Scenario.from_dict(base_data)

    window_s = _number(data.get("window_s", 0.5), "window_s")
    if window_s < 0:
        raise ConfigError("window_s", f"must be >= 0 (got {window_s:g})")
    chunk_size = _int(data.get("chunk_size", DEFAULT_CHUNK), "chunk_size")
    random = "samples" in data
    samples = _int(data["samples"], "samples") if random else 0
    seed = _int(data.get("seed", 0), "seed", lo=0)
    if "seed" in data and not random:
        raise ConfigError("seed", "only for a random sweep (with samples = N)")
    rng = np.random.default_rng(seed)

    axes_spec = data.get("axes")
    if not isinstance(axes_spec, dict) or not axes_spec:
        raise ConfigError("axes", "is required and needs at least one axis")
    axes = tuple(_axis_values(n, s, random, samples, rng) for n, s in axes_spec.items())
    targets: dict[str, str] = {}
    for a in axes:
        keys = (
            [".".join(a.path)]
            if a.kind == "path"
            else [CONVENIENCE_TARGET[a.kind]]
            if a.kind in CONVENIENCE
            else []
        )
        for key in keys:
            if key in targets:
                raise ConfigError(f"axes.{a.name}", f"sets {key}, as axis {targets[key]} does")
            targets[key] = a.name
    n_runs = samples if random else math.prod(len(a.values) for a in axes)
    heatmaps = _heatmaps(data.get("heatmap"), axes, random)
    sweep = Sweep(
        name=name,
        description=desc,
        base=base,
        base_data=base_data,
        axes=axes,
        random=random,
        n_runs=n_runs,
        seed=seed,
        window_s=window_s,
        chunk_size=chunk_size,
        heatmaps=heatmaps,
        source=text,
    )
    _validate(sweep)
    return sweep


def _validate(sweep: Sweep) -> None:
    """Build every axis value alone on the base, then every run: errors name the axis."""
    for a in sweep.axes:
        for v in a.points():
            try:
                _build_one_axis(sweep, a, v)
            except ConfigError as exc:
                raise ConfigError(f"axes.{a.name}", f"value {v!r} is rejected: {exc}") from None
    for i in range(sweep.n_runs):
        try:
            sweep.scenario(i)
        except ConfigError as exc:
            pt = ", ".join(
                f"{a.name} = {v!r}" for a, v in zip(sweep.axes, sweep.run_values(i), strict=True)
            )
            raise ConfigError(f"axes (run {i}: {pt})", str(exc)) from None


def _build_one_axis(sweep: Sweep, axis: Axis, value) -> Scenario:
    single = replace(sweep, axes=(replace(axis, values=(value,)),), random=False, n_runs=1)
    return single.scenario(0)


def load_sweep(ref: str) -> Sweep:
    """A built-in sweep by name, or a sweep file by path."""
    text, folder = sweep_text(ref)
    default = ref if folder is None else Path(ref).stem
    return parse_sweep(text, folder, default)


# ------------------------------------------------------------------------------------------
# running


def run_chunk(sweep: Sweep, j: int, chunk_size: int | None = None, parallel: bool = True):
    """Run chunk ``j`` of ``sweep``: its table (run, axis values, metrics), sorted by run."""
    import pandas as pd

    from imdrive.run.batch import simulate_batch

    runs = sweep.chunk_runs(j, chunk_size)
    inputs = sweep.inputs(runs)
    res = simulate_batch(
        (sweep.scenario(i) for i in runs), window_s=sweep.window_s, parallel=parallel
    )
    met = res.metrics.drop(columns=["drive"])
    return pd.concat([inputs, met], axis=1)


def _dask_chunk(sweep: Sweep, j: int, chunk_size: int):
    """Task body on a dask worker: one thread, no GIL (the worker's own parallelism rules)."""
    return j, run_chunk(sweep, j, chunk_size, parallel=False)


class Progress:
    """A plain progress bar on stderr, drawn only when stderr is a terminal."""

    def __init__(self, total: int, label: str, enabled: bool | None = None, stream=None):
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.total = total
        self.label = label
        self.done = 0
        self.start_done = 0
        self.t0 = time.perf_counter()

    def start(self, done: int) -> None:
        self.done = self.start_done = done
        self.t0 = time.perf_counter()
        self._draw()

    def advance(self, n: int) -> None:
        self.done += n
        self._draw()

    def close(self) -> None:
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()

    def _draw(self) -> None:
        if not self.enabled:
            return
        frac = self.done / self.total if self.total else 1.0
        width = 30
        bar = "#" * int(round(frac * width))
        el = time.perf_counter() - self.t0
        new = self.done - self.start_done
        eta = el / new * (self.total - self.done) if new else float("nan")
        self.stream.write(
            f"\r{self.label} [{bar:<{width}}] {self.done}/{self.total} runs {100 * frac:3.0f}% "
            f"{_hms(el)} elapsed, ETA {_hms(eta)}  "
        )
        self.stream.flush()


def _hms(s: float) -> str:
    if not math.isfinite(s):
        return "--:--"
    s = int(round(s))
    h, rem = divmod(s, 3600)
    m, sec = divmod(rem, 60)
    return f"{h}:{m:02d}:{sec:02d}" if h else f"{m:02d}:{sec:02d}"


class Store:
    """The sweep's folder: chunk files, manifest, consolidated table, figures."""

    MANIFEST = "manifest.json"

    def __init__(self, root: Path):
        self.root = Path(root)
        self.chunks = self.root / "chunks"

    def chunk_path(self, j: int) -> Path:
        return self.chunks / f"chunk-{j:06d}.parquet"

    def completed(self) -> set[int]:
        if not self.chunks.is_dir():
            return set()
        out = set()
        for p in self.chunks.iterdir():
            n = p.name
            if n.startswith("chunk-") and n.endswith(".parquet") and n[6:-8].isdigit():
                out.add(int(n[6:-8]))
        return out

    def read_manifest(self) -> dict | None:
        p = self.root / self.MANIFEST
        if not p.is_file():
            return None
        try:
            return json.loads(p.read_text())
        except (OSError, ValueError) as exc:
            raise ConfigError("--resume", f"cannot read {p}: {exc}") from None

    def _atomic_write(self, path: Path, write) -> None:
        tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
        write(tmp)
        os.replace(tmp, path)

    def write_manifest(self, sweep: Sweep, chunk_size: int, started: float) -> None:
        done = sorted(self.completed())
        info = {
            "format": 1,
            "sweep": sweep.name,
            "fingerprint": sweep.fingerprint(),
            "n_runs": sweep.n_runs,
            "chunk_size": chunk_size,
            "n_chunks": sweep.n_chunks(chunk_size),
            "completed_chunks": done,
            "complete": len(done) == sweep.n_chunks(chunk_size),
            "axes": [a.name for a in sweep.axes],
            "started": started,
            "updated": time.time(),
        }
        self._atomic_write(
            self.root / self.MANIFEST,
            lambda p: p.write_text(json.dumps(info, indent=2) + "\n"),
        )

    def write_chunk(self, j: int, df) -> None:
        self._atomic_write(self.chunk_path(j), lambda p: df.to_parquet(p, index=False))

    def clean_partials(self) -> None:
        for folder in (self.root, self.chunks):
            if folder.is_dir():
                for p in folder.iterdir():
                    if p.name.startswith(".") and ".tmp-" in p.name:
                        p.unlink(missing_ok=True)

    def consolidate(self, sweep: Sweep, chunk_size: int):
        import pandas as pd

        parts = [pd.read_parquet(self.chunk_path(j)) for j in range(sweep.n_chunks(chunk_size))]
        df = pd.concat(parts, ignore_index=True).sort_values("run", kind="stable")
        df = df.reset_index(drop=True)
        if len(df) != sweep.n_runs or not np.array_equal(df["run"], np.arange(sweep.n_runs)):
            raise RuntimeError(f"{self.root}: the chunks do not hold every run exactly once")
        self._atomic_write(self.root / "runs.parquet", lambda p: df.to_parquet(p, index=False))
        return df


def _open_store(sweep: Sweep, out: Path, resume: bool, chunk_size: int | None) -> tuple:
    store = Store(out)
    if out.exists() and not out.is_dir():
        raise ConfigError("--out", f"{out} exists and is not a folder")
    nonempty = out.is_dir() and any(out.iterdir())
    if nonempty and not resume:
        raise ConfigError(
            "--out", f"{out} exists and is not empty: add --resume to continue the sweep in it"
        )
    man = store.read_manifest() if nonempty else None
    if nonempty and man is None:
        raise ConfigError("--resume", f"{out} holds no {Store.MANIFEST}: not a sweep store")
    if man is not None:
        if man.get("fingerprint") != sweep.fingerprint():
            raise ConfigError(
                "--resume",
                f"{out} holds another sweep ({man.get('sweep')!r}, different base, axes or "
                "values): use a new --out folder",
            )
        if chunk_size is not None and chunk_size != man["chunk_size"]:
            raise ConfigError(
                "--chunk-size",
                f"the store was written with chunks of {man['chunk_size']} runs: "
                "resume with the same size (or omit --chunk-size)",
            )
        chunk_size = int(man["chunk_size"])
        started = man.get("started", time.time())
    else:
        chunk_size = chunk_size or sweep.chunk_size
        started = time.time()
    return store, chunk_size, started


def run_sweep(
    sweep: Sweep,
    out,
    *,
    scheduler: str | None = None,
    resume: bool = False,
    chunk_size: int | None = None,
    figures: bool = True,
    progress: bool | None = None,
    client=None,
):
    """Run ``sweep`` into the store ``out``; returns the consolidated table (pandas).

    ``scheduler`` is a dask.distributed scheduler address (or pass a ``client``); without
    either, chunks run here with the batch engine on all cores. ``progress`` None: a bar on
    stderr if it is a terminal.
    """
    out = Path(out)
    if chunk_size is not None:
        chunk_size = _int(chunk_size, "--chunk-size")
    store, cs, started = _open_store(sweep, out, resume, chunk_size)
    if client is None and scheduler is not None:
        client = _connect(scheduler)
        own_client = True
    else:
        own_client = False
    store.chunks.mkdir(parents=True, exist_ok=True)
    store.clean_partials()
    if sweep.source and not (store.root / "sweep.toml").exists():
        store._atomic_write(store.root / "sweep.toml", lambda p: p.write_text(sweep.source))
    store.write_manifest(sweep, cs, started)
    done = store.completed()
    pending = [j for j in range(sweep.n_chunks(cs)) if j not in done]
    bar = Progress(sweep.n_runs, f"sweep {sweep.name}", enabled=progress)
    bar.start(sum(len(sweep.chunk_runs(j, cs)) for j in done if j < sweep.n_chunks(cs)))
    try:
        if client is None:
            for j in pending:
                store.write_chunk(j, run_chunk(sweep, j, cs))
                store.write_manifest(sweep, cs, started)
                bar.advance(len(sweep.chunk_runs(j, cs)))
        elif pending:
            from dask.distributed import as_completed

            remote = client.scatter(sweep, broadcast=True)
            tag = f"imdrive-sweep-{sweep.fingerprint()[:8]}-{uuid.uuid4().hex[:8]}"
            futures = [
                client.submit(_dask_chunk, remote, j, cs, pure=False, key=f"{tag}-{j}")
                for j in pending
            ]
            for fut in as_completed(futures, loop=client.loop):
                j, df = fut.result()
                store.write_chunk(j, df)
                store.write_manifest(sweep, cs, started)
                bar.advance(len(df))
    finally:
        bar.close()
        if own_client:
            client.close()
    df = store.consolidate(sweep, cs)
    if figures:
        save_heatmaps(sweep, df, store.root / "figures")
    return df


def _connect(address: str):
    try:
        from dask.distributed import Client
    except ImportError:
        raise ConfigError(
            "--scheduler", "needs dask.distributed: pip install 'imdrive[dask]'"
        ) from None
    try:
        return Client(address, timeout="10s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ConfigError("--scheduler", f"cannot connect to {address}: {exc}") from None


# ------------------------------------------------------------------------------------------
# figures


def _aggregate(series, how: str):
    if how == "absmax":
        return series.abs().max()
    return getattr(series, how)()


def heatmap_figure(sweep: Sweep, df, h: Heatmap):
    """One heatmap (or a grid of them: ``rows`` x ``cols`` panels) of a metric over two axes."""
    from matplotlib.figure import Figure

    def levels(name):
        a = next(a for a in sweep.axes if a.name == name)
        return a.points()

    rows = levels(h.rows) if h.rows else [None]
    cols = levels(h.cols) if h.cols else [None]
    fig = Figure(figsize=(3.6 * len(cols) + 1.2, 3.0 * len(rows) + 0.8), layout="constrained")
    axs = fig.subplots(len(rows), len(cols), squeeze=False)
    vals = df[h.value].to_numpy(dtype=float)
    finite = vals[np.isfinite(vals)]
    signed = h.value in SIGNED_METRICS
    if finite.size:
        vmax = float(np.max(np.abs(finite))) if signed else float(finite.max())
        vmin = -vmax if signed else float(finite.min())
    else:
        vmin, vmax = -1.0, 1.0
    if vmin == vmax:
        vmin, vmax = vmin - 1.0, vmax + 1.0
    cmap = "RdBu_r" if signed else "viridis"
    mappable = None
    for r, rv in enumerate(rows):
        for c, cv in enumerate(cols):
            ax = axs[r, c]
            sel = df
            if h.rows:
                sel = sel[sel[h.rows] == rv]
            if h.cols:
                sel = sel[sel[h.cols] == cv]
            title = ", ".join(
                f"{n} = {_fmt(v)}" for n, v in ((h.rows, rv), (h.cols, cv)) if n is not None
            )
            ax.set_facecolor("0.85")
            if sweep.random:
                mappable = ax.scatter(
                    sel[h.x], sel[h.y], c=sel[h.value], cmap=cmap, vmin=vmin, vmax=vmax, s=18
                )
                ax.set_xlabel(h.x)
                ax.set_ylabel(h.y)
            else:
                xs, ys = levels(h.x), levels(h.y)
                g = sel.groupby([h.y, h.x], sort=False)[h.value].agg(
                    lambda s, how=h.agg: _aggregate(s, how)
                )
                Z = np.full((len(ys), len(xs)), np.nan)
                for (yv, xv), v in g.items():
                    Z[ys.index(yv), xs.index(xv)] = v
                mappable = ax.imshow(
                    np.ma.masked_invalid(Z),
                    origin="lower",
                    aspect="auto",
                    cmap=cmap,
                    vmin=vmin,
                    vmax=vmax,
                    interpolation="nearest",
                )
                ax.set_xticks(range(len(xs)), [_fmt(v) for v in xs], rotation=45)
                ax.set_yticks(range(len(ys)), [_fmt(v) for v in ys])
                ax.set_xlabel(h.x)
                ax.set_ylabel(h.y)
                if Z.size <= 100:
                    for (iy, ix), v in np.ndenumerate(Z):
                        if np.isfinite(v):
                            ax.text(ix, iy, _cell(v), ha="center", va="center", fontsize=6)
            if title:
                ax.set_title(title, fontsize=9)
    if mappable is not None:
        fig.colorbar(mappable, ax=axs, label=h.value, shrink=0.9)
    agg = "" if sweep.random else f" ({h.agg} over the other axes; grey: none finite)"
    fig.suptitle(f"{sweep.name}: {h.value}{agg}", fontsize=10)
    return fig


def _cell(v: float) -> str:
    a = abs(v)
    return f"{v:.0f}" if a >= 100 else f"{v:.1f}" if a >= 1 else f"{v:.2f}"


def _fmt(v) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def save_heatmaps(sweep: Sweep, df, folder: Path) -> list[Path]:
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for h in sweep.heatmaps:
        fig = heatmap_figure(sweep, df, h)
        extra = "".join(f"_by_{n}" for n in (h.rows, h.cols) if n)
        name = f"{h.value}__{h.y}_vs_{h.x}{extra}.png".replace("/", "_")
        path = folder / name
        fig.savefig(path, dpi=110)
        written.append(path)
    return written


# ------------------------------------------------------------------------------------------
# command line


def add_sweep_parser(sub) -> None:
    """Register ``imdrive sweep`` on the CLI's sub-parsers."""
    s = sub.add_parser(
        "sweep",
        help="run a parameter sweep into a Parquet store",
        description="Run a sweep (a built-in one by name, or a sweep TOML file): a Parquet "
        "table of summary metrics, one row per run, and heatmap figures.",
    )
    s.add_argument("sweep", nargs="?", metavar="SWEEP_OR_FILE")
    s.add_argument("--out", metavar="STORE", help="store folder (default out/sweep-NAME)")
    s.add_argument("--scheduler", metavar="ADDRESS", help="dask.distributed scheduler address")
    s.add_argument("--resume", action="store_true", help="continue an interrupted sweep")
    s.add_argument("--chunk-size", type=int, metavar="N", help="runs per chunk (default 32)")
    s.add_argument("--no-figures", action="store_true", help="skip the heatmap PNGs")
    s.add_argument("--dry-run", action="store_true", help="validate, print the size, run nothing")
    s.add_argument("--list", action="store_true", help="list the built-in sweeps")
    s.add_argument("--show", action="store_true", help="print the sweep file")
    s.add_argument("-q", "--quiet", action="store_true")
    s.set_defaults(func=cmd_sweep)


def cmd_sweep(args) -> int:
    if args.list:
        for n in sweep_names():
            text, _ = sweep_text(n)
            desc = tomllib.loads(text).get("description", "")
            print(f"  {n:<22} {desc}")
        return 0
    if not args.sweep:
        raise ConfigError("sweep", "name a built-in sweep (see --list) or a sweep file")
    if args.show:
        sys.stdout.write(sweep_text(args.sweep)[0])
        return 0
    if args.chunk_size is not None and args.chunk_size < 1:
        raise ConfigError("--chunk-size", f"must be >= 1 (got {args.chunk_size})")
    sweep = load_sweep(args.sweep)
    out = Path(args.out) if args.out else Path("out") / f"sweep-{sweep.name}"
    cs = args.chunk_size or sweep.chunk_size
    if args.dry_run:
        print(
            f"sweep {sweep.name}: {sweep.n_runs} runs "
            f"({' x '.join(str(n) for n in sweep.shape) if not sweep.random else 'random'}), "
            f"{sweep.n_chunks(cs)} chunks of {cs}, axes: {', '.join(a.name for a in sweep.axes)}"
        )
        return 0
    t0 = time.perf_counter()
    df = run_sweep(
        sweep,
        out,
        scheduler=args.scheduler,
        resume=args.resume,
        chunk_size=args.chunk_size,
        figures=not args.no_figures,
        progress=None if not args.quiet else False,
    )
    if not args.quiet:
        n_div = int(df["diverged"].sum())
        print(
            f"imdrive: sweep {sweep.name}: {len(df)} runs ({n_div} diverged) in "
            f"{time.perf_counter() - t0:.1f} s -> {out / 'runs.parquet'}",
            file=sys.stderr,
        )
    return 0


__all__ = [
    "Axis",
    "Heatmap",
    "Store",
    "Sweep",
    "add_sweep_parser",
    "load_sweep",
    "parse_sweep",
    "run_chunk",
    "run_sweep",
    "sweep_names",
]
