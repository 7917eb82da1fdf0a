"""Batch kernels: N independent drives over the cores, metrics folded in while the rows stream.

See :mod:`imdrive.run.batch` for the design and :mod:`imdrive.run.metrics` for the metric
definitions (this module is their streaming implementation; a test checks the two agree).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from imdrive.kernels.engine import LOG, S_OK, DriveParams, DriveState, run_drive
from imdrive.kernels.jit import njit
from imdrive.kernels.recording import RECORDING
from imdrive.kernels.records import b1, copy_row, f8, i8, record_dtype
from imdrive.kernels.threads import num_threads, over_threads  # noqa: F401  (num_threads: old path)

RPM = 2.0 * math.pi / 60.0
_INV_RPM = 1.0 / RPM  # the factor the result applies to rad/s columns
CONVERGENCE_BAND = 0.02

CHUNK = 1000  # control periods per engine call: bounds each thread's scratch log (240 kB)

#: One drive's metrics (see imdrive.run.metrics for each definition); the field names are the
#: columns of the batch table.
BATCH_METRICS = record_dtype(
    [
        ("speed_error_rpm", f8),
        ("speed_est_error_rpm", f8),
        ("speed_ripple_rpm", f8),
        ("torque_mean_Nm", f8),
        ("R2_hat_final_ohm", f8),
        ("R2_final_ohm", f8),
        ("R2_error_pct", f8),
        ("convergence_time_s", f8),
        ("peak_current_A", f8),
        ("final_speed_rpm", f8),
        ("final_speed_ref_rpm", f8),
        ("final_speed_est_rpm", f8),
        ("lost_control_at_s", f8),
        ("R2_held_pct", f8),
        ("R2_held_causes", f8),
        ("R2_held_since_s", f8),
        ("R2_held_end_causes", f8),
        ("R2_error_window_pct", f8),
        ("torque_limited_s", f8),
    ]
)
METRICS = BATCH_METRICS.names
N_METRICS = len(METRICS)

#: Running sums of the metrics while a drive's rows stream past, chunk by chunk.
ACCUMULATOR = record_dtype(
    [
        ("peak", f8),  # largest |i_s|, A
        ("last_bad", i8),  # last sample outside the R2 convergence band (-1: none)
        ("count", i8),  # samples in the steady-state window
        ("speed_err", f8),  # sums over the window, rpm
        ("speed_est_err", f8),
        ("torque", f8),  # N m
        ("speed_min", f8),  # rpm
        ("speed_max", f8),
        ("lc_start", i8),  # first sample of the current departure from the reference (-1: none)
        ("lc_at", i8),  # first sample of the first departure that lasted too long (-1: none)
        ("n_active", i8),  # samples with the compensator enabled (t >= its t_on)
        ("n_held", i8),  # of those, samples with R2_hat held (comp_frozen != 0)
        ("held_causes", i8),  # OR of the gating masks over the active samples
        ("held_start", i8),  # first sample of the present held stretch (-1: updating)
        ("held_run_causes", i8),  # OR of the masks over the present held stretch
        ("r2_peak", f8),  # signed relative R2 error of largest magnitude in the window
        ("lc_prev_speed", f8),  # the previous sample's speed, rad/s (NaN: none)
        ("n_limited", i8),  # samples out of the band while following at the torque limit
        ("lc_limited", i8),  # of them, in the current departure (not counted in its length)
        ("lc_best", f8),  # the current departure's speed closest to its reference so far, rad/s
        ("lc_away", b1),  # it fell back from there by the band: no sample of it is excused
    ]
)


class BatchOut(NamedTuple):
    """What the batch kernels write, one row per drive."""

    metrics: np.ndarray  # BATCH_METRICS[N]
    status: np.ndarray  # int64[N]: S_OK or a divergence code
    k_end: np.ndarray  # int64[N]: periods completed
    n_steps: np.ndarray  # int64[N] (input): control periods to run
    n_win: np.ndarray  # int64[N] (input): length of the steady-state window, periods
    lc_bound: np.ndarray  # float64[N] (input): loss-of-control speed bound, rad/s (<= 0: off)
    lc_n: np.ndarray  # int64[N] (input): loss-of-control duration, periods


@njit(cache=True)
def new_accumulator():
    acc = np.zeros(1, dtype=ACCUMULATOR)
    a = acc[0]
    a.last_bad = -1
    a.speed_min = np.inf
    a.speed_max = -np.inf
    a.lc_start = -1
    a.lc_at = -1
    a.lc_prev_speed = np.nan
    a.held_start = -1
    return acc


@njit(cache=True, inline="always")
def at_torque_limit(speed, speed_prev, speed_ref, id_ref, iq_ref, i_max):
    """Whether a sample follows its speed reference at the torque limit: the torque current
    at the current limit left by the flux current (``|iq*| >= 0.999 sqrt(I_max² - id*²)``),
    pushing towards the reference, and the speed moving towards it since the last sample
    (a stall or a runaway does not). Speeds in any one unit; currents A."""
    e = speed_ref - speed
    iq_max = math.sqrt(max(i_max * i_max - id_ref * id_ref, 0.0))
    return abs(iq_ref) >= 0.999 * iq_max and iq_ref * e > 0.0 and (speed - speed_prev) * e > 0.0


@njit(cache=True)
def accumulate(log, n_rows, k_first, k_win0, acc_arr, lc_bound=0.0, lc_n=0, t_on=np.inf, i_max=0.0):
    """Fold full-rate log rows ``0 .. n_rows-1`` (samples ``k_first ...``) into ``acc_arr[0]``.

    R2_hat held (samples with ``time >= t_on``, the compensator's enable time; ``inf``: no
    compensator): counts the samples whose gating mask ``comp_frozen`` is not 0, ORs the
    masks, and keeps the first sample and the mask of the present held stretch.

    Loss of control (``lc_bound > 0``, rad/s): a departure is a run of consecutive samples
    with ``|speed - speed_ref| > lc_bound``; the first that lasts ``lc_n`` periods or more
    (last sample minus first) sets ``acc.lc_at`` to its first sample. A departure in which
    the speed only heads for its reference is a lag: its samples following the reference at
    the torque limit (:func:`at_torque_limit`, with ``i_max > 0``; ``acc.n_limited`` counts
    them) are not counted in its length. Once the speed falls back from its closest approach
    by ``lc_bound`` the departure is not a lag (a stall, a runaway, a drive swinging out of
    control, which heads back at the limit too): every sample counts, from its first (Krause
    2250 hp's type-2 start swung 956 rpm off with 0.45 s of its 1.28 s at the limit).
    """
    acc = acc_arr[0]
    for r in range(n_rows):
        row = log[r]
        k = k_first + r
        if lc_bound > 0.0 and acc.lc_at < 0:
            e = row.speed_ref - row.speed
            if abs(e) > lc_bound:
                sigma = 1.0 if e > 0.0 else -1.0  # constant over a departure
                if acc.lc_start < 0:
                    acc.lc_start = k
                    acc.lc_limited = 0
                    acc.lc_best = row.speed
                    acc.lc_away = False
                if sigma * (row.speed - acc.lc_best) > 0.0:
                    acc.lc_best = row.speed
                elif sigma * (acc.lc_best - row.speed) > lc_bound:
                    acc.lc_away = True
                if i_max > 0.0 and at_torque_limit(
                    row.speed, acc.lc_prev_speed, row.speed_ref, row.id_ref, row.iq_ref, i_max
                ):
                    acc.n_limited += 1
                    acc.lc_limited += 1
                excused = 0 if acc.lc_away else acc.lc_limited
                if k - acc.lc_start - excused >= lc_n:
                    acc.lc_at = acc.lc_start
            else:
                acc.lc_start = -1
        acc.lc_prev_speed = row.speed
        if row.time >= t_on:
            acc.n_active += 1
            fl = int(row.comp_frozen)
            if fl != 0:
                acc.n_held += 1
                acc.held_causes |= fl
                if acc.held_start < 0:
                    acc.held_start = k
                    acc.held_run_causes = 0
                acc.held_run_causes |= fl
            else:
                acc.held_start = -1
        i_mag = math.sqrt(row.i_alpha**2 + row.i_beta**2)
        if i_mag > acc.peak:
            acc.peak = i_mag
        r2 = row.R2
        if not (abs(row.R2_hat - r2) / r2 <= CONVERGENCE_BAND):
            acc.last_bad = k
        if k >= k_win0:
            sp = row.speed * _INV_RPM
            acc.speed_err += sp - row.speed_ref * _INV_RPM
            acc.speed_est_err += row.speed_est * _INV_RPM - sp
            acc.torque += row.torque
            acc.speed_min = min(acc.speed_min, sp)
            acc.speed_max = max(acc.speed_max, sp)
            e2 = (row.R2_hat - r2) / r2
            if abs(e2) > abs(acc.r2_peak):
                acc.r2_peak = e2
            acc.count += 1


@njit(cache=True)
def summarize(acc, last, n_valid, ok, Ts, out):
    """The metrics record ``out`` from the accumulated sums and the last sample ``last``.

    ``n_valid`` is the number of samples seen; ``ok`` is False for a diverged drive (window
    metrics and convergence time are then NaN).
    """
    nan = np.nan
    cnt = acc.count
    if ok and cnt > 0:
        out.speed_error_rpm = acc.speed_err / cnt
        out.speed_est_error_rpm = acc.speed_est_err / cnt
        out.speed_ripple_rpm = acc.speed_max - acc.speed_min
        out.torque_mean_Nm = acc.torque / cnt
        out.R2_error_window_pct = 100.0 * acc.r2_peak
        if acc.last_bad == -1:
            out.convergence_time_s = 0.0
        elif acc.last_bad == n_valid - 1:
            out.convergence_time_s = nan
        else:
            out.convergence_time_s = (acc.last_bad + 1) * Ts  # the sample time, as the engine
    else:
        out.speed_error_rpm = nan
        out.speed_est_error_rpm = nan
        out.speed_ripple_rpm = nan
        out.torque_mean_Nm = nan
        out.R2_error_window_pct = nan
        out.convergence_time_s = nan
    out.R2_hat_final_ohm = last.R2_hat
    out.R2_final_ohm = last.R2
    out.R2_error_pct = 100.0 * (last.R2_hat - last.R2) / last.R2
    out.peak_current_A = acc.peak
    out.final_speed_rpm = last.speed * _INV_RPM
    out.final_speed_ref_rpm = last.speed_ref * _INV_RPM
    out.final_speed_est_rpm = last.speed_est * _INV_RPM
    out.lost_control_at_s = acc.lc_at * Ts if acc.lc_at >= 0 else nan
    out.torque_limited_s = acc.n_limited * Ts
    if acc.n_active > 0:
        out.R2_held_pct = 100.0 * acc.n_held / acc.n_active
        out.R2_held_causes = float(acc.held_causes)
        held = acc.held_start >= 0
        out.R2_held_since_s = acc.held_start * Ts if held else nan
        out.R2_held_end_causes = float(acc.held_run_causes) if held else 0.0
    else:
        out.R2_held_pct = nan
        out.R2_held_causes = nan
        out.R2_held_since_s = nan
        out.R2_held_end_causes = nan


@njit(cache=True)
def _drive_params(P, i):
    """Drive ``i``'s parameter rows as a one-drive :class:`DriveParams` (views, no copy)."""
    return DriveParams(
        P.sim[i : i + 1],
        P.plant[i : i + 1],
        P.inverter[i : i + 1],
        P.sensor[i : i + 1],
        P.control[i : i + 1],
        P.est[i : i + 1],
        P.comp[i : i + 1],
        P.prof_t[i : i + 1],
        P.prof_v[i : i + 1],
        P.prof_n[i : i + 1],
        P.tables,
        P.table_idx[i : i + 1],
        P.features,  # whole: the engine reads its type, not its rows
    )


@njit(cache=True)
def _own_state(S, i):
    """Drive ``i``'s state rows copied into arrays of its own (one row each)."""
    return DriveState(
        S.plant[i : i + 1].copy(),
        S.sample[i : i + 1].copy(),
        S.model[i : i + 1].copy(),
        S.control[i : i + 1].copy(),
        S.est[i : i + 1].copy(),
        S.comp[i : i + 1].copy(),
        S.inverter[i : i + 1].copy(),
    )


@njit(cache=True)
def _give_back(S, i, own):
    """Write the state :func:`_own_state` copied out back into drive ``i``'s rows."""
    copy_row(S.plant, i, own.plant, 0)
    copy_row(S.sample, i, own.sample, 0)
    copy_row(S.model, i, own.model, 0)
    copy_row(S.control, i, own.control, 0)
    copy_row(S.est, i, own.est, 0)
    copy_row(S.comp, i, own.comp, 0)
    copy_row(S.inverter, i, own.inverter, 0)


@njit(cache=True, inline="always")
def one_drive(loop, P, S, i, n_steps, n_win, log_out, log_every, metrics, scratch, lc_bound, lc_n):
    """Run drive ``i`` of the batch (:func:`run_one`, the drive ``loop``
    :func:`~imdrive.kernels.engine.run_drive`) on a copy of its state of its own.

    The drives' state records lie side by side in ``S``, and the threads run neighbouring
    drives at the same time: updated in place every period, two drives' records sharing a
    cache line would bounce it between the cores (false sharing). The copy is the thread's
    own memory; it goes back into ``S`` when the drive ends.
    """
    own = _own_state(S, i)
    status, k_end = run_one(
        loop, _drive_params(P, i), own, 0, n_steps, n_win, log_out, log_every, metrics, scratch,
        lc_bound, lc_n,
    )  # fmt: skip
    _give_back(S, i, own)
    return status, k_end


@njit(cache=True, inline="always")
def run_one(loop, P, S, i, n_steps, n_win, log_out, log_every, metrics, scratch, lc_bound, lc_n):
    """Run drive ``i`` at full rate, ``scratch.shape[0] - 1`` periods per engine call, folding
    each chunk into the metrics and copying its decimated rows into ``log_out``.

    Consecutive :func:`imdrive.kernels.engine.run_drive` calls with ``k0`` and ``final``
    reproduce one long call exactly, so the drive is bit-identical to ``simulate()``. Returns
    ``(status, k_end)`` as :func:`imdrive.kernels.engine.run_drive` does for the whole run.
    """
    chunk = scratch.shape[0] - 1
    # keep the array itself in use: a record taken from a local array does not keep the array
    # alive, and numba frees an array right after its last use
    acc_arr = new_accumulator()
    Ts = P.sim[i].Ts
    k_win0 = max(n_steps - n_win, 0)
    t_on = np.inf  # the compensator's start in the run's time, once it has started
    i_max = P.control[i].i_max  # torque-limited following is not a loss of control
    k0 = 0
    no_rec = np.zeros(0, dtype=RECORDING)  # simulate()'s type for "no recording"
    while True:
        steps = min(chunk, n_steps - k0)
        final = k0 + steps == n_steps
        # the engine with simulate()'s argument types: a constant here (i = 0 from
        # one_drive, log_every = 1) reached it as a numba literal, a signature of its own,
        # and every first batch compiled the whole engine again instead of loading run's.
        # Linked, not called through its address as the stability map does
        # (kernels/engine_call.py): optimised again with its callers here, the engine ran
        # the bench's 2000 one-second drives in 7.4 s of kernel against 10.4-10.8 s through
        # the address (2026-11-30, same results), for 2.5 s more of the first batch's compile
        status, ke = loop(
            P, S, np.int64(i), np.int64(steps), scratch, np.int64(1), np.int64(k0),
            np.bool_(final), no_rec,
        )  # fmt: skip
        ok = status == S_OK
        rows = ke + 1 if (ok and final) else ke
        if P.comp[i].enabled and S.comp[i].on:  # (the R1 test's wait moves it: stages.py)
            t_on = S.comp[i].t_start
        accumulate(scratch, rows, k0, k_win0, acc_arr, lc_bound, lc_n, t_on, i_max)
        for r in range(rows):
            k = k0 + r
            if k % log_every == 0 and k // log_every < log_out.shape[0]:
                copy_row(log_out, k // log_every, scratch, r)
        last = scratch[rows - 1]
        if not ok:
            k_end = k0 + ke
            summarize(acc_arr[0], last, k_end, False, Ts, metrics)
            return status, k_end
        k0 += steps
        if final:
            summarize(acc_arr[0], last, n_steps + 1, True, Ts, metrics)
            return status, n_steps


@njit(cache=True, entry=True, nogil=True)
def _worker(P, S, log, log_every, out, first, stride, scratch):
    """Drives ``first, first + stride, ...`` one after the other, sharing ``scratch``: the
    batch's one compiled entry point, the GIL released so that threads run it side by side."""
    _drives(run_drive, P, S, log, log_every, out, first, stride, scratch)


@njit  # never run: its types only
def _no_loop(P, S, i, n_steps, log, log_every, k0, final, rec):
    """:func:`~imdrive.kernels.engine.run_drive`'s signature and result types, doing nothing."""
    return np.int64(S_OK), n_steps


@njit  # not cached: only what it calls is kept
def worker_blocks(P, S, log, log_every, out, first, stride, scratch):
    """What :func:`_worker` calls besides the drive loop, with its argument types (the batch's
    record helpers, the metrics' accumulator): compiled, never run, by the cold-start helper
    process while this one compiles the loop (:func:`imdrive.run.prefetch.start_batch`)."""
    _drives(_no_loop, P, S, log, log_every, out, first, stride, scratch)


@njit(cache=True, inline="always")
def _drives(loop, P, S, log, log_every, out, first, stride, scratch):
    """:func:`_worker`'s body, the drive ``loop`` an argument (:func:`worker_blocks`)."""
    for n in range(first, P.sim.shape[0], stride):
        s, ke = one_drive(
            loop,
            P,
            S,
            n,
            out.n_steps[n],
            out.n_win[n],
            log[n],
            log_every,
            out.metrics[n],
            scratch,
            out.lc_bound[n],
            out.lc_n[n],
        )
        out.status[n] = s
        out.k_end[n] = ke


def new_scratch(n_slots: int, dtype=LOG) -> np.ndarray:
    """Scratch logs for ``n_slots`` workers, ``CHUNK + 1`` rows each, of the drives' log dtype."""
    return np.empty((n_slots, CHUNK + 1), dtype=dtype)


def batch_kernel(P, S, log, log_every, out, scratch):
    """``N`` drives over the cores (first axis of every array of ``P``, ``S``, ``out``).

    ``log`` is a ``[N, n_rows]`` log of the drives' log dtype (``n_rows`` may be 0, and
    at least the longest drive's rows otherwise), pre-filled with NaN; ``out`` gives each
    drive's number of periods and receives its metrics, status and periods done;
    ``S`` holds the final states on return. The drives are dealt to ``n_slots =
    scratch.shape[0]`` threads (``n, n + n_slots, ...``), each running the compiled
    :func:`_worker` with its row of ``scratch`` (:func:`new_scratch`) as the scratch log for
    all its drives.

    Threads of Python (:func:`imdrive.kernels.threads.over_threads`) rather than numba's
    ``prange``: the parallel loop was an entry point of its own, linking the worker and the
    engine and optimising them once more, and its unsigned index compiled the worker a second
    time. The first batch after a warm ``imdrive run`` compiled 11.1 s; with the threads
    3.5 s, its drives as fast (2026-11-30, benchmarks/README.md).
    """
    n_slots = scratch.shape[0]

    def slot_of(slot):
        _worker(P, S, log, log_every, out, slot, n_slots, scratch[slot])

    over_threads(slot_of, n_slots)


def batch_kernel_serial(P, S, log, log_every, out, scratch):
    """:func:`batch_kernel` on the calling thread only, releasing the GIL (for dask workers);
    ``scratch`` is one row of :func:`new_scratch`."""
    _worker(P, S, log, log_every, out, 0, 1, scratch)
