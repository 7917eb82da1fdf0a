"""Many drives at once: N independent drives in one call of the compiled loop, over the cores.

:func:`simulate_batch` takes scenarios (different machines, R2 errors, speeds, loads, ...) and
returns a :class:`BatchResult` whose ``metrics`` table has one row per drive, and optionally the
drives' decimated logs as :class:`~imdrive.result.SimulationResult` objects identical to what
:func:`imdrive.simulate.simulate` returns for each scenario alone.

Design
------
One compiled kernel (the worker of :func:`batch_kernel`, without the GIL;
:func:`batch_kernel_serial` runs it on the calling thread, for dask workers) deals the drives to
one worker per thread (worker ``w`` takes drives ``w, w + W, ...``). Each worker
allocates one scratch log of ``CHUNK + 1`` rows (240 kB) and reuses it for all its drives, so
memory scales with the number of threads, not with N nor with the length of a drive. For each
drive it

1. runs :func:`imdrive.engine.run_drive`, unchanged, ``CHUNK`` periods per call at full rate
   (``log_every = 1``) into the scratch log; with ``k0`` (the periods already done) and
   ``final`` (take the closing sample only at the end) consecutive calls reproduce one long
   call exactly, so the results are bit-identical to a single ``simulate()``;
2. folds each chunk's rows into running sums (:func:`accumulate`) that :func:`summarize` turns
   into the drive's row of the ``float64[N, N_METRICS]`` metrics array, and, on request, copies
   every ``log_every``-th row into the drive's slot of the output log (the rows a ``simulate()``
   at that ``log_every`` would log: logging does not feed back into the drive).

Logging at full rate into the small scratch and the streaming reduction cost about 5-10 % of
the kernel time (the dynamics dominate).

The Python side feeds the kernel blocks of ``block_size`` drives (default 512): per block it
builds and stacks the drives' records (:func:`imdrive.run.build.build_arrays`,
:func:`~imdrive.run.batch_groups.stack_drives`), grouped by R2 law (each has its own records,
and the kernel is compiled for them) and, with logs, by ``log_every``; drives of several
estimators share one kernel on the union of every estimator's records
(:mod:`imdrive.kernels.estimators.union`), one estimator alone keeps its own; each drive runs its
own number of periods (its sequence's: the premagnetisation and the torque-limited ramps
make it the drive's own); profiles with
different numbers of breakpoints are padded (the kernel reads ``prof_n`` of them); fuzzy tables
are shared (a small stack of the distinct tables plus an index per drive). A thread of its
own builds the next block (and judges the last one's status) while the kernels run a block
without the GIL: on two cores the set-up, 0.7 ms of Python per drive, had one core idle
(10,000 one-second drives: 29.7-31.3 s, 22 s of it kernel; overlapped, 26.7-27.3 s). Without
logs, what is
kept per drive is its metrics record and status: 13 float64 + 2 int64 = 120 bytes (plus pandas'
per-row cost of the final table, about the same again), so memory is linear in N at well under
1 kB per drive; the per-block arrays and the per-thread scratch logs are a fixed cost. With
``logs=True`` every drive's decimated log is kept,
``(n_steps // log_every + 1) * log_dtype(...).itemsize`` bytes
per drive (304 for an MRAS drive).

Metrics (columns of :attr:`BatchResult.metrics`): defined in :mod:`imdrive.run.metrics`; the
batch kernel computes them while the rows stream, and a test checks it against
:func:`imdrive.run.metrics.drive_metrics` on the same drives.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from imdrive.kernels.batch import (
    BATCH_METRICS,
    METRICS,
    _worker,
    batch_kernel,
    batch_kernel_serial,
    new_scratch,
)
from imdrive.kernels.engine import S_OK, DriveState
from imdrive.kernels.estimators import union
from imdrive.kernels.threads import num_threads, slots
from imdrive.run import prefetch
from imdrive.run.batch_groups import (
    first_call,
    group_args,
    own_rows,
    stack_drives,  # noqa: F401  (its import path of 0.1)
    united,
)
from imdrive.run.status import STATUS_COLUMNS

COLUMNS = (
    "drive",
    "status",
    "diverged",
    "diverged_at_s",
    "simulated_s",
    "lost_control",
    *METRICS,
    *STATUS_COLUMNS,
    "error",
)


def metrics_dtypes() -> dict[str, np.dtype]:
    """The numpy dtype of each column of the metrics table (:data:`COLUMNS`), as
    :func:`simulate_batch` builds it and as it reads back from Parquet."""
    out = {
        "drive": np.dtype(np.int64),
        "status": np.dtype(np.int64),
        "diverged": np.dtype(bool),
        "diverged_at_s": np.dtype(np.float64),
        "simulated_s": np.dtype(np.float64),
        "lost_control": np.dtype(bool),
    }
    out.update((name, BATCH_METRICS[name]) for name in METRICS)
    out["speed_error_pu_slip"] = np.dtype(np.float64)
    out["speed_tolerance_rpm"] = np.dtype(np.float64)
    out["verdict"] = np.dtype(object)
    out["verdict_ok"] = np.dtype(bool)
    out["verdict_text"] = np.dtype(object)
    out["verdict_at_s"] = np.dtype(np.float64)
    out["error"] = np.dtype(object)
    return out


#: ``status`` of a drive that could not be run (its derived parameters could not be computed,
#: or its scenario was refused when built): recorded with its message in ``error``, metrics NaN.
#: The kernel's own codes (``S_OK`` = 0, divergence 1-3) are never negative.
S_FAILED = -1


@dataclass(frozen=True)
class FailedRun:
    """An item of :func:`simulate_batch`'s input that stands for a run that could not be built.

    With ``errors="record"`` it becomes a row with ``status`` :data:`S_FAILED` and ``message``
    in the ``error`` column.
    """

    message: str


@dataclass
class BatchResult:
    """Outcome of :func:`simulate_batch`.

    Attributes
    ----------
    metrics : pandas.DataFrame
        One row per drive, in input order (columns :data:`COLUMNS`, see the module docstring).
    results : list[SimulationResult] | None
        With ``logs=True``: each drive's result, as ``simulate()`` returns it (decimated signals,
        final states, status); ``wall_time_s`` of each is 0 (the batch is timed as a whole).
    wall_time_s : float
        Wall time of the kernel calls (array building and result objects excluded).
    total_wall_s : float
        Wall time of the whole call.
    control_periods : int
        Control periods simulated, summed over the drives.
    """

    metrics: object
    results: list | None
    wall_time_s: float
    total_wall_s: float
    control_periods: int

    @property
    def n_drives(self) -> int:
        """Number of drives simulated (rows of ``metrics``)."""
        return len(self.metrics)

    @property
    def periods_per_s(self) -> float:
        """Throughput: drive-control-periods per second of kernel wall time."""
        return self.control_periods / self.wall_time_s if self.wall_time_s > 0 else math.inf


def _stack(items, log_every: int, n_rows: int, window_s: float, parallel: bool, est=None):
    """Run one group of (index, scenario, DriveArrays) sharing their records' dtypes (``est``:
    :func:`group_args`); return per-drive data."""
    params, state, log, out = group_args(items, n_rows, window_s, est)
    dtype = log.dtype
    G = len(items)
    t0 = time.perf_counter()
    if parallel:
        scratch = new_scratch(slots(G), dtype)
        batch_kernel(params, state, log, log_every, out, scratch)
    else:
        batch_kernel_serial(params, state, log, log_every, out, new_scratch(1, dtype)[0])
    wall = time.perf_counter() - t0
    return params, state, log, out, wall


class _Inline:
    """An executor that runs each call at once, on the calling thread (one core, or a batch
    asked to stay on its thread)."""

    def submit(self, fn, *args) -> Future:
        f: Future = Future()
        try:
            f.set_result(fn(*args))
        except BaseException as exc:  # raised again by f.result(), as a pool's would be
            f.set_exception(exc)
        return f

    def shutdown(self, wait=True, cancel_futures=False) -> None:
        pass


@dataclass
class _Block:
    """One block of drives between its three stages: built (:func:`_build_block`), run
    (:func:`_run_block`) and judged (:func:`_judge_block`); the per-drive arrays are in the
    block's order."""

    drives: list
    groups: dict | None  # (log_every, est dtype, comp dtype) -> [(index, scenario, arrays)]
    m: np.ndarray  # metrics
    s: np.ndarray  # status
    k: np.ndarray  # periods done
    ts: np.ndarray  # control period, s
    e: np.ndarray  # error message ("" when built)
    r1: np.ndarray  # the standstill R1 identification's last outcome
    results: list


def _next_block(it, block_size, offset, logs, log_every, window_s, errors) -> _Block | None:
    """The next ``block_size`` scenarios of ``it``, built (None when ``it`` is exhausted)."""
    block = []
    for sc in it:
        block.append(sc)
        if len(block) >= block_size:
            break
    return _build_block(block, offset, logs, log_every, window_s, errors) if block else None


def _build_block(block, offset, logs, log_every, window_s, errors) -> _Block:
    """Build one block of drives' arrays, grouped by kernel (see :func:`simulate_batch` for
    the arguments); a drive that cannot be built is recorded as failed (``errors="record"``)."""
    from imdrive.config.scenario import Scenario
    from imdrive.errors import ConfigError
    from imdrive.run.build import build_arrays

    B = len(block)
    blk = _Block(
        drives=block,
        groups={},
        m=np.empty(B, dtype=BATCH_METRICS),
        s=np.empty(B, dtype=np.int64),
        k=np.empty(B, dtype=np.int64),
        ts=np.empty(B),
        e=np.full(B, "", dtype=object),
        r1=np.full(B, np.nan),
        results=[None] * B,
    )
    for i, sc in enumerate(block):
        try:
            if isinstance(sc, FailedRun):
                raise ConfigError("scenario", sc.message)
            if not isinstance(sc, Scenario):
                raise ConfigError(
                    f"scenarios[{offset + i}]",
                    f"must be a Scenario, got {type(sc).__name__} (Scenario.read or "
                    "Scenario.from_dict make one)",
                )
            a = build_arrays(sc)
        except ConfigError as exc:
            if errors == "raise":
                raise
            for name in METRICS:
                blk.m[name][i] = np.nan
            blk.s[i], blk.k[i], blk.ts[i] = S_FAILED, 0, 0.0
            blk.e[i] = sc.message if isinstance(sc, FailedRun) else str(exc)
            continue
        le = (log_every or a.log_every) if logs else 1
        # one kernel call per decimation, estimator and R2 law (records); until 2026-11-30
        # per number of periods too, and since the drives' sequencing (premagnetisation,
        # torque-limited ramps) gives each drive its own, a batch ran one drive per call, on
        # one thread
        key = (int(le), a.params.est.dtype, a.params.comp.dtype)
        blk.groups.setdefault(key, []).append((i, sc, a))
    blk.groups = united(blk.groups)
    # kernels not yet compiled: a second process compiles from the last (or the one kernel's
    # late blocks)
    calls = [first_call(items, key, window_s) for key, items in blk.groups.items()]
    prefetch.start_batch(_worker, calls)
    return blk


def _run_block(blk: _Block, logs, window_s, parallel) -> float:
    """Run a built block's kernels (one call per group), fill its metrics, status and, with
    ``logs``, its results; return the kernels' wall time (s). The drives' arrays are let go."""
    from imdrive.run.result import SimulationResult
    from imdrive.run.simulate import logged_rows

    kernel_wall = 0.0
    for (le, est, _), items in blk.groups.items():
        n_rows = max(a.n_steps for _, _, a in items) // le + 1 if logs else 0
        params, state, log, out, wall = _stack(items, le, n_rows, window_s, parallel, est)
        kernel_wall += wall
        for g, (i, sc, a) in enumerate(items):
            blk.m[i] = out.metrics[g]
            blk.s[i] = out.status[g]
            blk.k[i] = out.k_end[g]
            blk.ts[i] = a.Ts
            blk.r1[i] = state.control[g]["dc_status"]
            if logs:
                own = log[g][: a.n_steps // le + 1]  # the rows of its own periods
                lg = logged_rows(own_rows(own, a.log), out.status[g], out.k_end[g], le)
                final = DriveState(*(f[g : g + 1].copy() for f in state))
                if final.est.dtype != a.state0.est.dtype:  # a union's: the drive's own
                    final = final._replace(est=union.from_union(final.est))
                blk.results[i] = SimulationResult.from_log(
                    sc,
                    lg,
                    a.state0,
                    final,
                    a.params,
                    int(out.status[g]),
                    int(out.k_end[g]),
                    0.0,
                    a.derived,
                )
    blk.groups = None
    return kernel_wall


def _judge_block(blk: _Block, window_s) -> dict:
    """A run block's status columns at once (a dict per drive kept to the end would cost
    ~0.6 kB)."""
    v = _verdicts(blk.drives, blk.m, blk.s, blk.k, blk.ts, blk.e, blk.r1, window_s)
    blk.drives = None  # a batch of 10^5 drives keeps no scenarios (with logs, the results do)
    return _status_columns(v)


def _verdicts(block, m_blk, s_blk, k_blk, ts_blk, e_blk, r1_blk, window_s=0.5) -> list[dict]:
    """The status columns (:func:`imdrive.run.status.verdict`) of each drive of a block
    (``r1_blk``: the standstill R1 identification's outcome, ``R1_id_status``, NaN without)."""
    from imdrive.run.status import verdict

    out = []
    for i, sc in enumerate(block):
        row = {name: float(m_blk[name][i]) for name in METRICS}
        simulated = float(k_blk[i] * ts_blk[i])
        row.update(
            status=int(s_blk[i]),
            simulated_s=simulated,
            diverged_at_s=simulated,
            error=e_blk[i],
            R1_id_status=float(r1_blk[i]),
            window_s=window_s,
        )
        if s_blk[i] == S_FAILED:
            out.append(
                {"speed_error_pu_slip": np.nan, "speed_tolerance_rpm": np.nan}
                | {
                    "verdict": "not-run",
                    "verdict_ok": False,
                    "verdict_text": f"not run: {e_blk[i]}",
                }
                | {"verdict_at_s": np.nan}
            )
        else:
            out.append(verdict(sc, row))
    return out


def _status_columns(verdicts: list[dict]) -> dict:
    """The status columns (:data:`~imdrive.run.status.STATUS_COLUMNS`) of the table."""
    kinds = metrics_dtypes()
    return {
        name: np.array([v[name] for v in verdicts], dtype=kinds[name]) for name in STATUS_COLUMNS
    }


def _joined_status(blocks: list[dict]) -> dict:
    """The status columns of every block (:func:`_status_columns`), end to end."""
    if not blocks:
        return _status_columns([])
    return {name: np.concatenate([b[name] for b in blocks]) for name in STATUS_COLUMNS}


def _is_int(v) -> bool:
    return isinstance(v, int | np.integer) and not isinstance(v, bool)


def _check_batch_arguments(log_every, window_s, block_size, errors) -> None:
    """:func:`simulate_batch`'s options checked, each refused by name."""
    from imdrive.errors import ConfigError

    if log_every is not None and not (_is_int(log_every) and log_every >= 1):
        raise ConfigError("log_every", f"must be an integer >= 1 (got {log_every!r})")
    if not (
        isinstance(window_s, int | float | np.floating)
        and not isinstance(window_s, bool)
        and math.isfinite(window_s)
        and window_s >= 0
    ):
        raise ConfigError("window_s", f"must be a finite number >= 0 (got {window_s!r})")
    if not (_is_int(block_size) and block_size >= 1):
        raise ConfigError("block_size", f"must be an integer >= 1 (got {block_size!r})")
    if errors not in ("raise", "record"):
        raise ConfigError("errors", f'must be "raise" or "record" (got {errors!r})')


def simulate_batch(
    scenarios: Iterable,
    *,
    logs: bool = False,
    log_every: int | None = None,
    window_s: float = 0.5,
    parallel: bool = True,
    block_size: int = 512,
    errors: str = "raise",
) -> BatchResult:
    """Simulate many independent drives at once.

    Parameters
    ----------
    scenarios : iterable of Scenario
        Consumed lazily, ``block_size`` at a time (a generator keeps memory bounded).
    logs : bool
        Also return each drive's decimated log as a ``SimulationResult`` in ``results``.
    log_every : int, optional
        Decimation of the returned logs; default each scenario's ``simulation.log_every``.
    window_s : float
        Length of the steady-state window of the metrics, s (see the module docstring).
    parallel : bool
        Use all numba threads (default); False runs on the calling thread without the GIL.
    block_size : int
        Drives per group of kernel calls (bounds the memory of the flat arrays).
    errors : {"raise", "record"}
        What a drive whose arrays cannot be built does (a :class:`~imdrive.errors.ConfigError`
        from :func:`~imdrive.run.build.build_arrays`, e.g. a derived gain that overflows):
        ``"raise"`` stops the batch; ``"record"`` gives it a row with ``status`` =
        :data:`S_FAILED` and the message in ``error``, and the other drives go on. A
        :class:`FailedRun` item is recorded the same way.

    Returns
    -------
    BatchResult
        The metrics table (one row per drive, input order), optional logs and timings.
    """
    import pandas as pd

    from imdrive.config.scenario import Scenario
    from imdrive.errors import ConfigError

    _check_batch_arguments(log_every, window_s, block_size, errors)
    t_start = time.perf_counter()
    kernel_wall = 0.0
    if isinstance(scenarios, Scenario | str | dict):
        raise ConfigError(
            "scenarios", "must be an iterable of Scenario objects (a list, a generator)"
        )
    try:
        it = iter(scenarios)
    except TypeError:
        raise ConfigError(
            "scenarios",
            f"must be an iterable of Scenario objects (a list, a generator), got "
            f"{type(scenarios).__name__}",
        ) from None
    # a block is built (and the previous one judged) on a thread of its own while the kernels
    # run the block before it without the GIL: the set-up no longer waits with a core idle
    offset, blocks = 0, []
    pool = ThreadPoolExecutor(1) if parallel and num_threads() > 1 else _Inline()
    try:
        built = pool.submit(_next_block, it, block_size, 0, logs, log_every, window_s, errors)
        while (blk := built.result()) is not None:
            offset += len(blk.drives)
            built = pool.submit(
                _next_block, it, block_size, offset, logs, log_every, window_s, errors
            )
            kernel_wall += _run_block(blk, logs, window_s, parallel)
            blocks.append((blk, pool.submit(_judge_block, blk, window_s)))
        verdicts = [judged.result() for _, judged in blocks]
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    results = [r for blk, _ in blocks for r in blk.results] if logs else None

    def joined(field, dtype):
        parts = [getattr(blk, field) for blk, _ in blocks]
        return np.concatenate(parts) if parts else np.empty(0, dtype=dtype)

    met, status, k_end = joined("m", BATCH_METRICS), joined("s", np.int64), joined("k", np.int64)
    Ts, err = joined("ts", np.float64), joined("e", object)
    blocks.clear()
    diverged = (status != S_OK) & (status != S_FAILED)
    simulated = k_end * Ts
    cols = {
        "drive": np.arange(offset, dtype=np.int64),
        "status": status,
        "diverged": diverged,
        "diverged_at_s": np.where(diverged, simulated, np.nan),
        "simulated_s": simulated,
        "lost_control": np.isfinite(met["lost_control_at_s"]),
    }
    for name in METRICS:
        cols[name] = np.ascontiguousarray(met[name])
    cols.update(_joined_status(verdicts))
    cols["error"] = err
    del met
    df = pd.DataFrame(cols, copy=False)
    return BatchResult(
        metrics=df,
        results=results,
        wall_time_s=kernel_wall,
        total_wall_s=time.perf_counter() - t_start,
        control_periods=int(k_end.sum()),
    )
