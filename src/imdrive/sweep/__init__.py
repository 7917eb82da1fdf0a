"""Parameter sweeps: many runs of one base scenario, on this machine or on a dask cluster.

``imdrive sweep SWEEP --out STORE`` reads a sweep file (or a built-in sweep by name, e.g.
``detuning-map``), runs every point with the batch engine (:mod:`imdrive.run.batch`) and
writes a tidy Parquet table, one row per run: the run index, the value of every axis and the
summary metrics of :mod:`imdrive.run.batch` (speed error, estimate error, ripple, R2 estimate
and its error, convergence time, peak current, divergence), plus heatmap figures.

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
    "load.torque_Nm.changes[0].at" = [1.5, 2.5]        # one element of a profile, as --set
    [axes.variant]                                     # named sets of overrides
    plain = {}
    paper = { compensator.enabled = true, compensator.t_on_s = 4.0 }

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

    * ``R2_ratio``  — R2_hat/R2: sets ``estimator.R2_ratio`` (the starting R2_hat is the value
      times the run's ``machine.R2_ohm``; an ``estimator.R2_ohm`` of the base is dropped);
    * ``R1_ratio``  — R1_hat/R1: the same for ``estimator.R1_ratio``;
    * ``"machine.preset"`` — machines of the library (``{ values = ["krause-50hp", ...] }``):
      every setting the base leaves derived or states in per-unit follows each run's machine
      (docs/machine-envelope.md);
    * ``speed_rpm`` — the final speed reference: sets the value of the last breakpoint of
      ``control.speed_ref_rpm`` (the base's ramp or step then ends at this speed);
    * ``load_Nm``   — the final load: the same for ``load.torque_Nm``;
    * ``speed_pu``, ``load_pu`` — the same in per-unit of the run's machine: times its rated
      speed (rpm) and rated torque (N m) (:func:`imdrive.config.rated.rated_point`), so one
      sweep means the same operating points on every machine of the library;
    * ``load_pu_available`` — the final load in per-unit of the torque the machine delivers
      at the run's final speed reference on rated voltage (rated torque up to rated speed,
      then constant power, bounded by the breakdown torque:
      :func:`imdrive.sweep.model.available_torque_Nm`), so a cell above base speed asks for
      a load the machine can carry;
    * any name whose value is a table of tables — a set axis: each entry names a set of
      overrides (``{}`` for none), its name is what the table records.

    For each run, a set axis's overrides are applied first, then the key-path axes (set on the
    base's TOML dictionary and validated once, as ``imdrive run --set`` does), then
    ``R2_ratio``, ``R1_ratio``, ``speed_rpm``, ``load_Nm``, ``speed_pu``, ``load_pu``,
    ``load_pu_available``. Two
    axes may not set the same key (nor a table and a key inside it), whichever their kinds: a
    set axis's keys are those any of its sets overrides.

Bad input (an unknown key or parameter, an empty axis, ``min > max``, a value a scenario
rejects, an unsafe ``name``, more runs than ``max_runs``) raises
:class:`~imdrive.errors.ConfigError` naming the field before anything runs. The size is
computed from the axes before any value is built (``--max-runs``, default 10 000 000); then
every distinct scenario is built and validated, derived quantities included (the
``speed_rpm`` and ``load_Nm`` axes only change a profile's last value, so a million-run grid
builds few scenarios; beyond 20 000 distinct ones each axis value is validated alone and the
combinations as they run). A run that diverges is recorded (``diverged = True``, ``status``,
``diverged_at_s``; window metrics NaN), and so is a run that cannot be built or whose derived
parameters overflow (``status`` = -1, its message in ``error``); the others go on.

Store
-----
``STORE/chunks/chunk-NNNNNN.parquet`` holds runs ``[N*chunk_size, (N+1)*chunk_size)``; each is
written to a temporary name and renamed into place (atomic), then ``STORE/manifest.json`` (sweep
name, fingerprint of the resolved sweep, number of runs, chunk size, completed chunks and the
sha256 of each) is rewritten the same way; every file is fsynced before its rename and its
folder after. A writer holds ``STORE/.lock`` (``flock``): a second process on the same store
fails at once. ``--resume`` reads every chunk back and recomputes those missing or damaged
(unreadable, other columns or column types, not exactly its runs, axis values that are not the
sweep's, a sha256 other than the one recorded or none), saying so; the checksums are checked
again before the table is assembled, so an interrupted sweep loses at most the chunks in
progress and duplicates nothing; without it, a non-empty STORE is an error. At the end the
chunks are read back, sorted by run and written as ``STORE/runs.parquet``; the figures go to
``STORE/figures/``; only then does the manifest say ``"complete": true``. A run's results do not
depend on which chunk, process or machine computed it, so a resumed or distributed sweep gives
the same table as a local, uninterrupted one.

Execution: locally (default) each chunk is one call of the batch engine over all cores. With
``--scheduler ADDRESS`` (needs ``pip install 'imdrive[dask]'``) every chunk is a task on that
dask.distributed cluster (``Client(ADDRESS)``), run on one worker thread without the GIL; the
workers return the chunk's table and this process writes the store. The address is checked
first (:mod:`imdrive.sweep.scheduler`: its form, its protocol, for TCP a dask scheduler's
greeting within ``--connect-timeout``, 10 s by default): a port that is not a scheduler (an
HTTP server, silence, garbage) is bad input, one line, before any client is made.

Modules
-------
imdrive.sweep.spec
    The sweep file: :class:`Sweep`, :class:`Axis`, :class:`Heatmap`, :func:`parse_sweep`,
    :func:`load_sweep`, each run's scenario.
imdrive.sweep.store
    The Parquet store and resuming.
imdrive.sweep.run
    :func:`run_sweep`: local or dask execution, with a progress bar.
imdrive.sweep.scheduler
    Connecting to a dask scheduler: the address, its greeting, the client.
imdrive.sweep.figures
    The heatmaps.
imdrive.cli
    The ``imdrive sweep`` command itself.
"""

from imdrive.sweep.figures import heatmap_figure, save_heatmaps
from imdrive.sweep.run import Progress, run_chunk, run_sweep
from imdrive.sweep.spec import (
    Axis,
    Heatmap,
    Sweep,
    load_sweep,
    parse_sweep,
    sweep_names,
    sweep_text,
)
from imdrive.sweep.spec import _apply as _apply  # tests: a run's override equals --set
from imdrive.sweep.store import Store

__all__ = [
    "Axis",
    "Heatmap",
    "Progress",
    "Store",
    "Sweep",
    "heatmap_figure",
    "load_sweep",
    "parse_sweep",
    "run_chunk",
    "run_sweep",
    "save_heatmaps",
    "sweep_names",
    "sweep_text",
]
