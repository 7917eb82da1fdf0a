"""Run one drive: the compiled loop over a scenario's arrays, and its result."""

from __future__ import annotations

import time

import numpy as np

from imdrive.config.scenario import Scenario
from imdrive.kernels import layout as Lo
from imdrive.kernels.engine import run_drive
from imdrive.run.build import DriveArrays, build_arrays
from imdrive.run.result import SimulationResult

__all__ = ["DriveArrays", "build_arrays", "logged_rows", "simulate"]


def logged_rows(log: np.ndarray, status: int, k_end: int, log_every: int) -> np.ndarray:
    """The rows of a NaN-prefilled kernel log that were written (all of them unless diverged)."""
    if status == Lo.S_OK:
        return log
    log = log[: k_end // log_every + 1]
    return log[~np.isnan(log[:, Lo.L_TIME])]


def simulate(scenario: Scenario, arrays: DriveArrays | None = None) -> SimulationResult:
    """Run one drive and return its :class:`~imdrive.result.SimulationResult`.

    A run whose states diverge is not an exception: the result has ``diverged = True``, the
    time and the signal, and the logged rows up to that point.
    """
    a = arrays if arrays is not None else build_arrays(scenario)
    n_rows = a.n_steps // a.log_every + 1
    log = np.full((n_rows, Lo.N_LOG), np.nan)
    x = a.x0.copy()
    c = a.c0.copy()
    # a zero-length call loads (or compiles) the kernel, so wall_time_s measures the run alone
    t0 = time.perf_counter()
    run_drive(a.par, a.prof_t, a.prof_v, a.prof_n, a.table, x.copy(), c.copy(), 0, log[:0], 1)
    startup = time.perf_counter() - t0
    t0 = time.perf_counter()
    status, k_end = run_drive(
        a.par, a.prof_t, a.prof_v, a.prof_n, a.table, x, c, a.n_steps, log, a.log_every
    )
    wall = time.perf_counter() - t0
    log = logged_rows(log, status, k_end, a.log_every)
    res = SimulationResult.from_log(
        scenario, log, a.x0, x, c, a.par, int(status), int(k_end), wall, a.derived
    )
    res.startup_s = startup
    return res
