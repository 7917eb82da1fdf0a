"""Batch kernels: N independent drives over the cores, metrics folded in while the rows stream.

See :mod:`imdrive.run.batch` for the design and the metric definitions.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import njit, prange

from imdrive.kernels import layout as Lo
from imdrive.kernels.engine import run_drive

RPM = 2.0 * math.pi / 60.0
_INV_RPM = 1.0 / RPM  # the factor result.py applies to rad/s columns
CONVERGENCE_BAND = 0.02

CHUNK = 1000  # control periods per engine call: bounds each thread's scratch log (240 kB)

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


# --------------------------------------------------------------------------------------------
# kernels


# running sums of the metrics while a drive's rows stream past, chunk by chunk
A_PEAK = 0
A_LAST_BAD = 1  # last sample outside the R2 convergence band (-1: none)
A_COUNT = 2  # samples in the steady-state window
A_SPEED_ERR = 3
A_SPEED_EST_ERR = 4
A_TORQUE = 5
A_MIN = 6
A_MAX = 7
N_ACC = 8


@njit(cache=True)
def accumulator():
    acc = np.zeros(N_ACC)
    acc[A_LAST_BAD] = -1.0
    acc[A_MIN] = np.inf
    acc[A_MAX] = -np.inf
    return acc


@njit(cache=True)
def accumulate(log, n_rows, k_first, k_win0, acc):
    """Fold full-rate log rows ``0 .. n_rows-1`` (samples ``k_first ...``) into ``acc``."""
    for r in range(n_rows):
        row = log[r]
        k = k_first + r
        i_mag = math.sqrt(row[Lo.L_I_A] ** 2 + row[Lo.L_I_B] ** 2)
        if i_mag > acc[A_PEAK]:
            acc[A_PEAK] = i_mag
        r2 = row[Lo.L_R2]
        if not (abs(row[Lo.L_R2_HAT] - r2) / r2 <= CONVERGENCE_BAND):
            acc[A_LAST_BAD] = k
        if k >= k_win0:
            sp = row[Lo.L_W_M] * _INV_RPM
            acc[A_SPEED_ERR] += sp - row[Lo.L_W_REF] * _INV_RPM
            acc[A_SPEED_EST_ERR] += row[Lo.L_W_HAT] * _INV_RPM - sp
            acc[A_TORQUE] += row[Lo.L_TE]
            acc[A_MIN] = min(acc[A_MIN], sp)
            acc[A_MAX] = max(acc[A_MAX], sp)
            acc[A_COUNT] += 1.0


@njit(cache=True)
def summarize(acc, last, n_valid, ok, Ts, out):
    """The metrics row ``out`` (N_METRICS) from the accumulated sums and the last sample.

    ``n_valid`` is the number of samples seen; ``ok`` is False for a diverged drive (window
    metrics and convergence time are then NaN).
    """
    nan = np.nan
    cnt = acc[A_COUNT]
    if ok and cnt > 0:
        out[M_SPEED_ERR] = acc[A_SPEED_ERR] / cnt
        out[M_SPEED_EST_ERR] = acc[A_SPEED_EST_ERR] / cnt
        out[M_RIPPLE] = acc[A_MAX] - acc[A_MIN]
        out[M_TORQUE] = acc[A_TORQUE] / cnt
        last_bad = int(acc[A_LAST_BAD])
        if last_bad == -1:
            out[M_CONV] = 0.0
        elif last_bad == n_valid - 1:
            out[M_CONV] = nan
        else:
            out[M_CONV] = (last_bad + 1) * Ts  # the sample time, as the engine computes it
    else:
        out[M_SPEED_ERR] = nan
        out[M_SPEED_EST_ERR] = nan
        out[M_RIPPLE] = nan
        out[M_TORQUE] = nan
        out[M_CONV] = nan
    out[M_R2_HAT] = last[Lo.L_R2_HAT]
    out[M_R2] = last[Lo.L_R2]
    out[M_R2_ERR] = 100.0 * (last[Lo.L_R2_HAT] - last[Lo.L_R2]) / last[Lo.L_R2]
    out[M_PEAK_I] = acc[A_PEAK]
    out[M_SPEED] = last[Lo.L_W_M] * _INV_RPM
    out[M_SPEED_REF] = last[Lo.L_W_REF] * _INV_RPM
    out[M_SPEED_EST] = last[Lo.L_W_HAT] * _INV_RPM


@njit(cache=True)
def one_drive(
    par, prof_t, prof_v, prof_n, table, x, c, n_steps, n_win, log_out, log_every, metrics, scratch
):
    """Run one drive at full rate, ``scratch.shape[0] - 1`` periods per engine call, folding
    each chunk into the metrics and copying its decimated rows into ``log_out``.

    Consecutive :func:`imdrive.engine.run_drive` calls with ``k0`` and ``final`` reproduce one
    long call exactly, so the drive is bit-identical to ``simulate()``. Returns
    ``(status, k_end)`` as :func:`imdrive.engine.run_drive` does for the whole run.
    """
    chunk = scratch.shape[0] - 1
    acc = accumulator()
    last = np.empty(Lo.N_LOG)
    k_win0 = max(n_steps - n_win, 0)
    k0 = 0
    while True:
        steps = min(chunk, n_steps - k0)
        final = k0 + steps == n_steps
        status, ke = run_drive(
            par, prof_t, prof_v, prof_n, table, x, c, steps, scratch, 1, k0, final
        )
        ok = status == Lo.S_OK
        rows = ke + 1 if (ok and final) else ke
        accumulate(scratch, rows, k0, k_win0, acc)
        for r in range(rows):
            k = k0 + r
            if k % log_every == 0 and k // log_every < log_out.shape[0]:
                log_out[k // log_every, :] = scratch[r, :]
        last[:] = scratch[rows - 1, :]
        if not ok:
            k_end = k0 + ke
            summarize(acc, last, k_end, False, par[Lo.P_TS], metrics)
            return status, k_end
        k0 += steps
        if final:
            summarize(acc, last, n_steps + 1, True, par[Lo.P_TS], metrics)
            return status, n_steps


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
        scratch = np.empty((CHUNK + 1, Lo.N_LOG))
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
    scratch = np.empty((CHUNK + 1, Lo.N_LOG))
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


def num_threads() -> int:
    """Threads numba's parallel kernels use."""
    return numba.get_num_threads()
