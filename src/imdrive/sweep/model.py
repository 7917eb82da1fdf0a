"""A sweep's model: its axes, heatmaps and runs (:class:`Sweep`, :class:`Axis`,
:class:`Heatmap`), the constants of the sweep file, and how each run's scenario is built from
the base (:meth:`Sweep.scenario`).

Pure Python on top of :mod:`imdrive.config`; :mod:`imdrive.sweep.spec` reads a sweep file into
these objects.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
from dataclasses import dataclass, field, replace

import numpy as np

from imdrive.config.pairs import set_layer
from imdrive.config.profiles import Profile
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError

CONVENIENCE = (
    "R2_ratio",
    "R1_ratio",
    "speed_rpm",
    "load_Nm",
    "speed_pu",
    "load_pu",
    "load_pu_available",
)
CONVENIENCE_TARGET = {
    "R2_ratio": "estimator.R2_ratio",
    "R1_ratio": "estimator.R1_ratio",
    "speed_rpm": "control.speed_ref_rpm",
    "load_Nm": "load.torque_Nm",
    "speed_pu": "control.speed_ref_rpm",
    "load_pu": "load.torque_Nm",
    "load_pu_available": "load.torque_Nm",
}
#: the convenience axes that change only a profile's last value (cheap to validate)
PROFILE_AXES = ("speed_rpm", "load_Nm", "speed_pu", "load_pu", "load_pu_available")
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
    set_layer(data, [(tuple(parts), value)], "the sweep axis")
    return Scenario.from_dict(data)


def _with_final(profile: Profile, value: float) -> Profile:
    """``profile`` with the value of its last breakpoint set to ``value``."""
    pts = list(profile.points)
    pts[-1] = (pts[-1][0], float(value))
    return Profile(tuple(pts))


class _Draft:
    """A point's scenario while its convenience axes are applied: each axis replaces a section
    (validated as a section), and the scenario is validated once, by :meth:`scenario`; it reads
    as the scenario so far (``draft.control``, ``draft.machine``).

    One validation per point instead of one per axis: the whole scenario's rules ran 3 times for
    a sweep over R2_ratio, speed and load, about half of the set-up time of a batch.
    """

    def __init__(self, sc: Scenario):
        self._base = sc
        self._sections: dict = {}

    def __getattr__(self, name):  # only for names that are not the draft's own
        if name.startswith("_"):
            raise AttributeError(name)
        sections = self._sections
        return sections[name] if name in sections else getattr(self._base, name)

    def set(self, **sections) -> None:
        """Replace whole sections (``control=...``)."""
        self._sections.update(sections)

    def scenario(self) -> Scenario:
        """The validated scenario."""
        return replace(self._base, **self._sections) if self._sections else self._base


def _with_R2_ratio(sc: _Draft, ratio: float) -> None:
    # as a ratio, so it follows the machine of the run (a machine axis may change it)
    sc.set(estimator=replace(sc.estimator, R2_ohm=None, R2_ratio=ratio))


def _with_R1_ratio(sc: _Draft, ratio: float) -> None:
    sc.set(estimator=replace(sc.estimator, R1_ohm=None, R1_ratio=ratio))


def _with_speed(sc: _Draft, rpm: float) -> None:
    # in rpm: the base's profile (per-unit or not) in rpm, ending at this speed
    from imdrive.config.profile_units import stated_speed_ref_rpm

    profile = _with_final(stated_speed_ref_rpm(sc), rpm)
    sc.set(control=replace(sc.control, speed_ref_rpm=profile, speed_ref_pu=None))


def _with_load(sc: _Draft, torque: float) -> None:
    from imdrive.config.profile_units import stated_load_Nm

    profile = _with_final(stated_load_Nm(sc), torque)
    sc.set(load=replace(sc.load, torque_Nm=profile, torque_pu=None))


def _rated(sc):
    from imdrive.config.rated import rated_point

    return rated_point(sc.machine)


def _with_speed_pu(sc: _Draft, pu: float) -> None:
    # in per-unit of the run's machine's rated speed (config/rated.py), so it follows the machine
    ctl = sc.control
    if ctl.speed_ref_pu is None:
        _with_speed(sc, pu * _rated(sc).speed_rpm)
        return
    sc.set(control=replace(ctl, speed_ref_pu=_with_final(ctl.speed_ref_pu, pu)))


def _with_load_pu(sc: _Draft, pu: float) -> None:
    if sc.load.torque_pu is None:
        _with_load(sc, pu * _rated(sc).torque_Nm)
        return
    sc.set(load=replace(sc.load, torque_pu=_with_final(sc.load.torque_pu, pu)))


def available_torque_Nm(sc: Scenario) -> float:
    """The torque the run's machine delivers at the final speed reference on rated voltage, N m.

    Up to the rated speed the rated torque; above it the rated power's torque
    ``T_rated w_rated / w`` (field weakening at rated voltage: constant power), but never more
    than the breakdown torque, which falls as ``(w_rated / w)^2`` at constant voltage (the
    circuit's, :func:`imdrive.config.rated.rated_point`). Example: Table IV at twice its rated
    speed, 0.5 of its rated torque (its breakdown torque over four is higher).
    """
    from imdrive.config.rated import rated_point

    rp = rated_point(sc.machine)
    from imdrive.config.profile_units import stated_speed_ref_rpm

    x = abs(stated_speed_ref_rpm(sc).points[-1][1]) / rp.speed_rpm
    if x <= 1.0:
        return rp.torque_Nm
    return min(rp.torque_Nm / x, rp.breakdown_torque_Nm / (x * x))


def _with_load_pu_available(sc: _Draft, pu: float) -> None:
    # after the speed axes: the torque available depends on the run's speed
    _with_load(sc, pu * available_torque_Nm(sc))


# the convenience axes, applied in this order after the overrides
CONVENIENCE_APPLY = {
    "R2_ratio": _with_R2_ratio,
    "R1_ratio": _with_R1_ratio,
    "speed_rpm": _with_speed,
    "load_Nm": _with_load,
    "speed_pu": _with_speed_pu,
    "load_pu": _with_load_pu,
    "load_pu_available": _with_load_pu_available,
}


def _number(value, path: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(path, f"must be a finite number, got {value!r}")
    return float(value)


def _build(sweep: Sweep, point: dict) -> Scenario:
    """The scenario of one point (axis name -> value) of ``sweep``."""
    draft = _Draft(_overridden(sweep, point))
    for kind, apply in CONVENIENCE_APPLY.items():
        for a in sweep.axes:
            if a.kind == kind:
                apply(draft, _number(point[a.name], f"axes.{a.name}"))
    return draft.scenario()


def _overridden(sweep: Sweep, point: dict) -> Scenario:
    """The base with the set axes' overrides, then the key-path axes, of ``point`` (cached)."""
    axes = [a for a in sweep.axes if a.kind in ("sets", "path")]
    key = tuple(repr(point[a.name]) for a in axes)
    sc = sweep._scenarios.get(key)
    if sc is None:
        data = copy.deepcopy(sweep.base_data)
        # the point's overrides are one layer on the base: an axis over one member of a pair
        # clears the other in the base (config/pairs.py), two axes setting both are refused
        items = [pv for a in axes if a.kind == "sets" for pv in a.sets[point[a.name]]]
        items += [(a.path, point[a.name]) for a in axes if a.kind == "path"]
        set_layer(data, items, "the sweep's axes")
        sc = Scenario.from_dict(data)
        if len(sweep._scenarios) >= _CACHE_MAX:
            sweep._scenarios.clear()
        sweep._scenarios[key] = sc
    return sc
