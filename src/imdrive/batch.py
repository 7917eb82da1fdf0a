"""Many drives at once: N independent drives in one call of the compiled loop, over the cores.

:func:`simulate_batch` takes scenarios (different machines, R2 errors, speeds, loads, ...) and
returns a :class:`BatchResult` whose ``metrics`` table has one row per drive, and optionally the
drives' decimated logs as :class:`~imdrive.result.SimulationResult` objects identical to what
:func:`imdrive.simulate.simulate` returns for each scenario alone.

Design
------
One compiled kernel (:func:`batch_kernel`, numba ``parallel=True``; :func:`batch_kernel_serial`
is the same loop on one thread, without the GIL, for dask workers) deals the drives to one
parallel worker per thread (``prange``; worker ``w`` takes drives ``w, w + W, ...``). Each worker
allocates one scratch log of ``n_steps + 1`` rows and reuses it for all its drives, so memory
scales with the number of threads and the length of one drive, not with N. For each drive it

1. runs :func:`imdrive.engine.run_drive` **once, unchanged, over the whole run** at full rate
   (``log_every = 1``) into the scratch log. The drive's arithmetic is therefore exactly that of
   a single ``simulate()`` call: results are bit-identical by construction. (Splitting the run
   into chunks of a few hundred periods would bound the scratch to a chunk, but ``run_drive``
   restarts its time ``t = k Ts`` and its compensator counter ``k`` at 0 on every call and runs
   the controller once more at the final sample without integrating, so chunked calls are *not*
   identical to one call; that would need an engine change, see below);
2. reduces the scratch log to the drive's row of the ``float64[N, N_METRICS]`` metrics array
   (:func:`summarize`, one streaming pass), and, on request, copies every ``log_every``-th row
   into the drive's slot of the output log (the rows a ``simulate()`` at that ``log_every``
   would log: logging does not feed back into the drive).

Reusing the scratch matters for long drives: a fresh 34 MB scratch per 14 s drive is a fresh
``mmap`` whose page faults cost a third of the run time. Logging at full rate and the summary
pass cost about 5-10 % of the kernel time (the dynamics dominate).

The Python side feeds the kernel blocks of ``block_size`` drives (default 512): per block it
builds and stacks the flat arrays (:func:`imdrive.simulate.build_arrays`), grouped by number of
periods (one ``n_steps`` per kernel call) and, with logs, by ``log_every``; profiles with
different numbers of breakpoints are padded (the kernel reads ``prof_n`` of them); fuzzy tables
are shared (a small stack of the distinct tables plus an index per drive). Without logs, what is
kept per drive is its metrics row and status: 12 float64 + 3 int64 = 120 bytes (plus pandas'
per-row cost of the final table, about the same again), so memory is linear in N at well under
1 kB per drive; the per-block arrays and the per-thread scratch logs are bounded (the scratch is
``(n_steps + 1) * N_LOG * 8`` bytes, 2.4 MB for a 1 s drive at 100 us). With ``logs=True`` every
drive's decimated log is kept, ``(n_steps // log_every + 1) * 240`` bytes per drive.

An engine change that would bound the scratch by a chunk instead of the run length (not needed
for correctness or for the figures measured in ``benchmarks/``): ``run_drive(..., k0, final)``
with the time and compensator index ``k0 + k`` and, when ``final`` is 0, a return after the
integration of period ``n_steps - 1`` without the extra sample at ``k = n_steps``.

Metrics (columns of :attr:`BatchResult.metrics`)
------------------------------------------------
All are computed from the full-rate samples ``k = 0 ... K`` (``K = n_steps`` for a complete run,
``t_k = k Ts``), i.e. the rows a ``simulate()`` with ``log_every = 1`` logs. Speeds are
mechanical, in rpm; ``speed`` is the plant's, ``speed_ref`` the reference (0 in open loop),
``speed_est`` the MRAS estimate (0 in open loop, the measured-speed drives also run the MRAS).
The *window* is the samples ``k >= n_steps - round(window_s / Ts)`` (the last ``window_s``
seconds, both ends included; the whole run if ``window_s >= t_end``).

``speed_error_rpm``      mean of ``speed - speed_ref`` over the window
``speed_est_error_rpm``  mean of ``speed_est - speed`` over the window
``speed_ripple_rpm``     ``max(speed) - min(speed)`` over the window
``torque_mean_Nm``       mean electromagnetic torque over the window
``R2_hat_final_ohm``     the rotor-resistance estimate at the last sample
``R2_final_ohm``         the plant's rotor resistance at the last sample (scale and temperature)
``R2_error_pct``         ``100 (R2_hat - R2) / R2`` at the last sample
``convergence_time_s``   the first sample time after which ``|R2_hat - R2| / R2 <= 2 %`` at
                         every sample to the end (``R2`` the plant's at each sample): 0 if it
                         holds throughout, NaN if it does not hold at the last sample
``peak_current_A``       ``max sqrt(i_alpha^2 + i_beta^2)`` of the plant's stator current over
                         all samples
``final_speed_rpm``, ``final_speed_ref_rpm``, ``final_speed_est_rpm``   at the last sample

plus ``status`` (0 ok, else the :mod:`imdrive.layout` divergence code), ``diverged``,
``diverged_at_s`` (the time the divergence was found, ``k_end Ts``; NaN if not diverged) and
``simulated_s`` (``k_end Ts``). For a diverged drive the samples are those logged before the
divergence: the window metrics and ``convergence_time_s`` are NaN (no steady state was reached),
the final values and ``peak_current_A`` are those of the last sample before the divergence.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import dataclass

import numba
import numpy as np
from numba import njit, prange

from imdrive import layout as Lo
from imdrive.engine import run_drive

RPM = 2.0 * math.pi / 60.0
_INV_RPM = 1.0 / RPM  # the factor result.py applies to rad/s columns
CONVERGENCE_BAND = 0.02

# metric columns, in the order of the kernel's metrics array
M_SPEED_ERR = 0
M_SPEED_EST_ERR = 1
M_RIPPLE = 2
M_TORQUE = 3
M_R2_HAT = 4
M_R2 = 5
M_R2_ERR = 6
M_CONV = 7
M_PEAK_I = 8
M_SPEED = 9
M_SPEED_REF = 10
M_SPEED_EST = 11
N_METRICS = 12

METRICS = (
    "speed_error_rpm",
    "speed_est_error_rpm",
    "speed_ripple_rpm",
    "torque_mean_Nm",
    "R2_hat_final_ohm",
    "R2_final_ohm",
    "R2_error_pct",
    "convergence_time_s",
    "peak_current_A",
    "final_speed_rpm",
    "final_speed_ref_rpm",
    "final_speed_est_rpm",
)
COLUMNS = ("drive", "status", "diverged", "diverged_at_s", "simulated_s", *METRICS)


# --------------------------------------------------------------------------------------------
# kernels


@njit(cache=True)
def summarize(log, n_valid, k_win0, ok, out):
    """Reduce full-rate log rows ``0 .. n_valid-1`` to one metrics row ``out`` (N_METRICS).

    ``k_win0`` is the first sample of the steady-state window; ``ok`` is False for a diverged
    drive (window metrics and convergence time are then NaN).
    """
    nan = np.nan
    peak = 0.0
    last_bad = -1
    cnt = 0
    s_err = 0.0
    s_est = 0.0
    s_te = 0.0
    w_min = np.inf
    w_max = -np.inf
    for r in range(n_valid):
        row = log[r]
        i_mag = math.sqrt(row[Lo.L_I_A] ** 2 + row[Lo.L_I_B] ** 2)
        if i_mag > peak:
            peak = i_mag
        r2 = row[Lo.L_R2]
        if not (abs(row[Lo.L_R2_HAT] - r2) / r2 <= CONVERGENCE_BAND):
            last_bad = r
        if r >= k_win0:
            sp = row[Lo.L_W_M] * _INV_RPM
            s_err += sp - row[Lo.L_W_REF] * _INV_RPM
            s_est += row[Lo.L_W_HAT] * _INV_RPM - sp
            s_te += row[Lo.L_TE]
            w_min = min(w_min, sp)
            w_max = max(w_max, sp)
            cnt += 1
    last = log[n_valid - 1]
    if ok and cnt > 0:
        out[M_SPEED_ERR] = s_err / cnt
        out[M_SPEED_EST_ERR] = s_est / cnt
        out[M_RIPPLE] = w_max - w_min
        out[M_TORQUE] = s_te / cnt
        if last_bad == -1:
            out[M_CONV] = 0.0
        elif last_bad == n_valid - 1:
            out[M_CONV] = nan
        else:
            out[M_CONV] = log[last_bad + 1, Lo.L_TIME]
    else:
        out[M_SPEED_ERR] = nan
        out[M_SPEED_EST_ERR] = nan
        out[M_RIPPLE] = nan
        out[M_TORQUE] = nan
        out[M_CONV] = nan
    out[M_R2_HAT] = last[Lo.L_R2_HAT]
    out[M_R2] = last[Lo.L_R2]
    out[M_R2_ERR] = 100.0 * (last[Lo.L_R2_HAT] - last[Lo.L_R2]) / last[Lo.L_R2]
    out[M_PEAK_I] = peak
    out[M_SPEED] = last[Lo.L_W_M] * _INV_RPM
    out[M_SPEED_REF] = last[Lo.L_W_REF] * _INV_RPM
    out[M_SPEED_EST] = last[Lo.L_W_HAT] * _INV_RPM


@njit(cache=True)
def one_drive(
    par, prof_t, prof_v, prof_n, table, x, c, n_steps, n_win, log_out, log_every, metrics, scratch
):
    """Run one drive at full rate into ``scratch`` (n_steps + 1 rows), summarize it, copy the
    decimated rows into ``log_out``.

    Returns ``(status, k_end)`` as :func:`imdrive.engine.run_drive`.
    """
    status, k_end = run_drive(par, prof_t, prof_v, prof_n, table, x, c, n_steps, scratch, 1)
    n_valid = n_steps + 1 if status == Lo.S_OK else k_end
    summarize(scratch, n_valid, max(n_steps - n_win, 0), status == Lo.S_OK, metrics)
    for r in range(log_out.shape[0]):
        k = r * log_every
        if k >= n_valid:
            break
        for j in range(Lo.N_LOG):
            log_out[r, j] = scratch[k, j]
    return status, k_end


@njit(cache=True, nogil=True)
def _worker(
    par,
    prof_t,
    prof_v,
    prof_n,
    tables,
    table_idx,
    x,
    c,
    n_steps,
    n_win,
    log,
    log_every,
    metrics,
    status,
    k_end,
    first,
    stride,
    scratch,
):
    """Drives ``first, first + stride, ...`` one after the other, sharing ``scratch``."""
    for n in range(first, par.shape[0], stride):
        s, ke = one_drive(
            par[n],
            prof_t[n],
            prof_v[n],
            prof_n[n],
            tables[table_idx[n]],
            x[n],
            c[n],
            n_steps,
            n_win[n],
            log[n],
            log_every,
            metrics[n],
            scratch,
        )
        status[n] = s
        k_end[n] = ke


@njit(cache=True, parallel=True)
def batch_kernel(
    par,
    prof_t,
    prof_v,
    prof_n,
    tables,
    table_idx,
    x,
    c,
    n_steps,
    n_win,
    log,
    log_every,
    metrics,
    status,
    k_end,
    n_slots,
):
    """``N`` drives over the cores (first axis of every array is the drive).

    ``tables`` is float64[T, 13, 13] with ``table_idx`` int64[N] choosing each drive's table;
    ``n_win`` int64[N] the window length in periods; ``log`` float64[N, n_rows, N_LOG]
    (``n_rows`` may be 0), pre-filled with NaN; ``metrics`` float64[N, N_METRICS], ``status``
    and ``k_end`` int64[N] are outputs; ``x`` and ``c`` hold the final states on return.
    The drives are dealt to ``n_slots`` parallel workers (``n, n + n_slots, ...``), each with
    one scratch log for all its drives.
    """
    for slot in prange(n_slots):
        scratch = np.empty((n_steps + 1, Lo.N_LOG))
        _worker(
            par,
            prof_t,
            prof_v,
            prof_n,
            tables,
            table_idx,
            x,
            c,
            n_steps,
            n_win,
            log,
            log_every,
            metrics,
            status,
            k_end,
            slot,
            n_slots,
            scratch,
        )


@njit(cache=True, nogil=True)
def batch_kernel_serial(
    par,
    prof_t,
    prof_v,
    prof_n,
    tables,
    table_idx,
    x,
    c,
    n_steps,
    n_win,
    log,
    log_every,
    metrics,
    status,
    k_end,
):
    """:func:`batch_kernel` on the calling thread only, releasing the GIL (for dask workers)."""
    scratch = np.empty((n_steps + 1, Lo.N_LOG))
    _worker(
        par,
        prof_t,
        prof_v,
        prof_n,
        tables,
        table_idx,
        x,
        c,
        n_steps,
        n_win,
        log,
        log_every,
        metrics,
        status,
        k_end,
        0,
        1,
        scratch,
    )


# --------------------------------------------------------------------------------------------
# Python API


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
        return len(self.metrics)

    @property
    def periods_per_s(self) -> float:
        """Throughput: drive-control-periods per second of kernel wall time."""
        return self.control_periods / self.wall_time_s if self.wall_time_s > 0 else math.inf


def _stack(items, log_every: int, n_rows: int, window_s: float, parallel: bool):
    """Run one group of (index, scenario, DriveArrays) sharing n_steps; return per-drive data."""
    G = len(items)
    arrays = [a for _, _, a in items]
    n_steps = arrays[0].n_steps
    K = max(a.prof_t.shape[1] for a in arrays)
    par = np.empty((G, Lo.N_PAR))
    prof_t = np.zeros((G, Lo.N_PROF, K))
    prof_v = np.zeros((G, Lo.N_PROF, K))
    prof_n = np.empty((G, Lo.N_PROF), dtype=np.int64)
    x = np.empty((G, Lo.NX))
    c = np.empty((G, Lo.NC))
    n_win = np.empty(G, dtype=np.int64)
    table_idx = np.empty(G, dtype=np.int64)
    tables: list[np.ndarray] = []
    seen: dict[bytes, int] = {}
    for g, a in enumerate(arrays):
        par[g] = a.par
        k = a.prof_t.shape[1]
        prof_t[g, :, :k] = a.prof_t
        prof_v[g, :, :k] = a.prof_v
        prof_n[g] = a.prof_n
        x[g] = a.x0
        c[g] = a.c0
        n_win[g] = int(round(window_s / a.par[Lo.P_TS]))
        key = a.table.tobytes()
        if key not in seen:
            seen[key] = len(tables)
            tables.append(np.ascontiguousarray(a.table, dtype=np.float64))
        table_idx[g] = seen[key]
    tab = np.stack(tables)
    log = np.full((G, n_rows, Lo.N_LOG), np.nan)
    metrics = np.empty((G, N_METRICS))
    status = np.empty(G, dtype=np.int64)
    k_end = np.empty(G, dtype=np.int64)
    args = (
        par,
        prof_t,
        prof_v,
        prof_n,
        tab,
        table_idx,
        x,
        c,
        n_steps,
        n_win,
        log,
        log_every,
        metrics,
        status,
        k_end,
    )
    t0 = time.perf_counter()
    if parallel:
        batch_kernel(*args, max(min(G, numba.get_num_threads()), 1))
    else:
        batch_kernel_serial(*args)
    wall = time.perf_counter() - t0
    return par, x, c, log, metrics, status, k_end, wall


def simulate_batch(
    scenarios: Iterable,
    *,
    logs: bool = False,
    log_every: int | None = None,
    window_s: float = 0.5,
    parallel: bool = True,
    block_size: int = 512,
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

    Returns
    -------
    BatchResult
    """
    import pandas as pd

    from imdrive.errors import ConfigError
    from imdrive.result import SimulationResult
    from imdrive.simulate import build_arrays, logged_rows

    if log_every is not None and (isinstance(log_every, bool) or int(log_every) < 1):
        raise ConfigError("log_every", f"must be >= 1 (got {log_every})")
    if not (math.isfinite(window_s) and window_s >= 0):
        raise ConfigError("window_s", f"must be >= 0 (got {window_s})")
    if block_size < 1:
        raise ConfigError("block_size", f"must be >= 1 (got {block_size})")
    t_start = time.perf_counter()
    chunks_m, chunks_s, chunks_k, chunks_ts = [], [], [], []
    results: list = []
    kernel_wall = 0.0
    it = iter(scenarios)
    offset = 0
    while True:
        block = []
        for sc in it:
            block.append(sc)
            if len(block) >= block_size:
                break
        if not block:
            break
        B = len(block)
        m_blk = np.empty((B, N_METRICS))
        s_blk = np.empty(B, dtype=np.int64)
        k_blk = np.empty(B, dtype=np.int64)
        ts_blk = np.empty(B)
        res_blk: list = [None] * B
        groups: dict[tuple[int, int], list] = {}
        for i, sc in enumerate(block):
            a = build_arrays(sc)
            le = (log_every or a.log_every) if logs else 1
            groups.setdefault((a.n_steps, int(le)), []).append((i, sc, a))
        for (n_steps, le), items in groups.items():
            n_rows = n_steps // le + 1 if logs else 0
            par, x, c, log, met, st, ke, wall = _stack(items, le, n_rows, window_s, parallel)
            kernel_wall += wall
            for g, (i, sc, a) in enumerate(items):
                m_blk[i] = met[g]
                s_blk[i] = st[g]
                k_blk[i] = ke[g]
                ts_blk[i] = a.par[Lo.P_TS]
                if logs:
                    lg = logged_rows(log[g], st[g], ke[g], le)
                    res_blk[i] = SimulationResult.from_log(
                        sc, lg, a.x0, x[g], c[g], a.par, int(st[g]), int(ke[g]), 0.0, a.derived
                    )
        chunks_m.append(m_blk)
        chunks_s.append(s_blk)
        chunks_k.append(k_blk)
        chunks_ts.append(ts_blk)
        if logs:
            results.extend(res_blk)
        offset += B
    if offset:
        met = np.concatenate(chunks_m)
        status = np.concatenate(chunks_s)
        k_end = np.concatenate(chunks_k)
        Ts = np.concatenate(chunks_ts)
        del chunks_m, chunks_s, chunks_k, chunks_ts
    else:
        met = np.empty((0, N_METRICS))
        status = np.empty(0, dtype=np.int64)
        k_end = np.empty(0, dtype=np.int64)
        Ts = np.empty(0)
    diverged = status != Lo.S_OK
    simulated = k_end * Ts
    cols = {
        "drive": np.arange(offset, dtype=np.int64),
        "status": status,
        "diverged": diverged,
        "diverged_at_s": np.where(diverged, simulated, np.nan),
        "simulated_s": simulated,
    }
    for j, name in enumerate(METRICS):
        cols[name] = np.ascontiguousarray(met[:, j])
    del met
    df = pd.DataFrame(cols, copy=False)
    return BatchResult(
        metrics=df,
        results=results if logs else None,
        wall_time_s=kernel_wall,
        total_wall_s=time.perf_counter() - t_start,
        control_periods=int(k_end.sum()),
    )
