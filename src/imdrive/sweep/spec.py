"""The sweep specification: reading, validating and expanding a sweep file.

The objects it builds are in :mod:`imdrive.sweep.model`, the parsing of axes and heatmaps in
:mod:`imdrive.sweep.axes`; this module re-exports their public names.

A sweep file (format in :mod:`imdrive.sweep`) names a base scenario, overrides for every run and
axes; :func:`parse_sweep` turns it into a :class:`Sweep`, which knows the value of every axis of
every run (:meth:`Sweep.run_values`) and builds each run's scenario (:meth:`Sweep.scenario`).
Every run's scenario is built and validated when the sweep is read, so bad input raises
:class:`~imdrive.errors.ConfigError` naming the field before anything runs.

Notes
-----
A run's scenario goes through the same override mechanism as ``imdrive run --set``
(:func:`imdrive.config.pairs.set_layer` on the base's TOML dictionary, then
:meth:`Scenario.from_dict <imdrive.config.scenario.Scenario.from_dict>`); only the convenience
axes ``R2_ratio``, ``R1_ratio``, ``speed_rpm`` and ``load_Nm`` then replace fields of the
validated scenario.
Pure Python on top of :mod:`imdrive.config`; only checking the metric names of ``[[heatmap]]``
tables loads the run layer (:data:`imdrive.run.batch.COLUMNS`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace
from importlib import resources
from pathlib import Path

import numpy as np

from imdrive.config.overrides import parse_toml
from imdrive.config.pairs import set_layer
from imdrive.config.plugins import allowing_plugins, resolve_plugin_paths
from imdrive.config.presets import scenario_text
from imdrive.config.scenario import FILE_KEYS, Scenario
from imdrive.config.validation import check_name, slug
from imdrive.errors import ConfigError, check_argument
from imdrive.sweep.axes import _axes, _flatten, _heatmaps, _int
from imdrive.sweep.model import (  # noqa: F401  (re-exports: the public names of the sweep file)
    AGGREGATES,
    CONVENIENCE,
    CONVENIENCE_APPLY,
    CONVENIENCE_TARGET,
    DEFAULT_CHUNK,
    DEFAULT_MAX_RUNS,
    PROFILE_AXES,
    TOP_KEYS,
    VALIDATE_ALL_MAX,
    Axis,
    Heatmap,
    Sweep,
    _apply,
    _build,
    _number,
    _overridden,
)

__all__ = [
    "AGGREGATES",
    "CONVENIENCE",
    "CONVENIENCE_TARGET",
    "DEFAULT_CHUNK",
    "DEFAULT_MAX_RUNS",
    "TOP_KEYS",
    "VALIDATE_ALL_MAX",
    "Axis",
    "Heatmap",
    "Sweep",
    "load_sweep",
    "parse_sweep",
    "sweep_names",
    "sweep_text",
]


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
    import os

    from imdrive.config.presets import MAX_TOML_BYTES
    from imdrive.config.user_files import path_form_problem, read_user_text

    problem = path_form_problem(ref)
    if problem is not None:
        raise ConfigError("sweep", f"not a usable file path: {problem}")
    if not os.path.lexists(ref):
        raise ConfigError(
            "sweep",
            f"{ref[:60]!r} is neither a built-in sweep ({', '.join(sweep_names())}) nor a file",
        )
    return read_user_text(ref, "sweep", MAX_TOML_BYTES, "sweep file"), Path(ref).resolve().parent


def sweep_description(name: str) -> str:
    """The description of built-in sweep ``name``, read from its file without building its
    scenarios (``imdrive presets`` lists them; building is for running them, and warns about
    what they state: a deprecated spelling of a sweep that keeps one)."""
    text, _ = sweep_text(name)
    return _name_and_description(_read_toml(text), name)[1]


def parse_sweep(
    text: str,
    folder: Path | None = None,
    default_name: str = "sweep",
    max_runs: int = DEFAULT_MAX_RUNS,
    *,
    allow_plugins: bool | None = None,
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
    allow_plugins : bool, optional
        True: import the modules its scenario lists in ``[plugins] modules`` (their code
        runs; relative paths from the sweep file's folder); default: only with
        ``IMDRIVE_ALLOW_PLUGINS=1`` (:mod:`imdrive.config.plugins`).

    Returns
    -------
    Sweep
        The resolved, validated sweep.
    """
    with allowing_plugins(allow_plugins):
        return _parse_sweep(text, folder, default_name, max_runs)


def _parse_sweep(text, folder, default_name, max_runs) -> Sweep:
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
    data = parse_toml(text, "sweep")
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
    from imdrive.config.user_files import lexists

    if folder is not None and not Path(base_ref).is_absolute() and lexists(folder / base_ref):
        base_ref = str(folder / base_ref)
    try:
        base_data = parse_toml(scenario_text(base_ref, FILE_KEYS), "base", base_ref)
    except ConfigError as exc:
        raise ConfigError("base", exc.rule) from None
    if Path(base_ref).suffix == ".toml":  # a file: its plug-in paths from its folder
        resolve_plugin_paths(base_data, Path(base_ref).parent)
    sets = data.get("set", {})
    if not isinstance(sets, dict):
        raise ConfigError("set", "must be a table of scenario keys")
    items = _flatten(sets, "set")
    if folder is not None:  # the sweep file's own plug-in paths from its folder
        for k, (parts, value) in enumerate(items):
            if tuple(parts) == ("plugins", "modules") and isinstance(value, list):
                table = {"plugins": {"modules": value}}
                resolve_plugin_paths(table, folder)
                items[k] = (parts, table["plugins"]["modules"])
    set_layer(base_data, items, "[set]")  # one layer on the base (pairs)
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
            if a.kind not in PROFILE_AXES:
                derived(sc, f"{a.name} = {v!r}")
    joint = [k for k, a in enumerate(sweep.axes) if a.kind not in PROFILE_AXES]
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


def load_sweep(
    ref: str, max_runs: int | None = None, *, allow_plugins: bool | None = None
) -> Sweep:
    """A built-in sweep by name, or a sweep file by path.

    Parameters
    ----------
    ref : str
        A name of :func:`sweep_names` or a path.
    max_runs : int, optional
        Refuse a sweep of more runs (default :data:`DEFAULT_MAX_RUNS`).
    allow_plugins : bool, optional
        Import the plug-in modules its scenario lists (:func:`parse_sweep`).

    Returns
    -------
    Sweep
        The resolved, validated sweep.
    """
    import os

    check_argument(ref, (str, os.PathLike), "ref", "a built-in sweep's name or a file path")
    ref = os.fspath(ref)
    if max_runs is not None:
        check_argument(max_runs, int, "max_runs", "an integer")
    text, folder = sweep_text(ref)
    default = ref if folder is None else slug(Path(ref).stem)
    return parse_sweep(
        text,
        folder,
        default,
        DEFAULT_MAX_RUNS if max_runs is None else max_runs,
        allow_plugins=allow_plugins,
    )
