"""Run one drive: the compiled loop over a scenario's arrays, and its result."""

from __future__ import annotations

import time

import numpy as np

from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.kernels.engine import LOG, S_OK, run_drive
from imdrive.kernels.recording import RECORDING
from imdrive.run import prefetch
from imdrive.run.build import DriveArrays, build_arrays, copy_state
from imdrive.run.result import SimulationResult, columns_from_log

__all__ = ["DriveArrays", "build_arrays", "logged_rows", "new_log", "simulate"]


def logged_rows(log: np.ndarray, status: int, k_end: int, log_every: int) -> np.ndarray:
    """The rows of a NaN-prefilled kernel log that were written (all of them unless diverged)."""
    if status == S_OK:
        return log
    log = log[: k_end // log_every + 1]
    return log[~np.isnan(log["time"])]


def new_log(n_rows, dtype: np.dtype | None = None) -> np.ndarray:
    """A kernel log of ``n_rows`` rows, NaN-filled (unwritten rows stay recognisable).

    Parameters
    ----------
    n_rows : int or tuple of int
        Rows (a batch's: ``(drives, rows)``).
    dtype : numpy.dtype, optional
        The drive's log record (``DriveArrays.log``; default: an MRAS drive's, ``LOG``).

    Returns
    -------
    numpy.ndarray
        The log records, every value NaN.
    """
    dtype = np.dtype(LOG if dtype is None else dtype)
    floats = all(dtype.fields[n][0] == np.float64 for n in dtype.names)
    if not floats or dtype.itemsize != 8 * len(dtype.names):  # other types, or padding
        return np.full(n_rows, np.nan, dtype=dtype)
    # every field a float: filled as one float array; numpy's np.full casts NaN field by
    # field, element by element (bench-estimators' batch log, 180 drives of 10001 rows,
    # 605 MB: 0.04 s against 0.17-0.67 s)
    log = np.empty(n_rows, dtype=dtype)
    log.view(np.float64).fill(np.nan)
    return log


def kernels_cached() -> bool:
    """Whether the drive kernel is compiled in this process or cached on disk (so the next run
    starts without compiling); True when that cannot be told."""
    try:
        if run_drive.signatures:
            return True
        import os

        return os.path.exists(run_drive._cache._cache_file._index_path)
    except Exception:  # numba internals changed: say nothing rather than something wrong
        return True


def simulate(
    scenario: Scenario, arrays: DriveArrays | None = None, record: bool | None = None
) -> SimulationResult:
    """Run one drive.

    A run whose states diverge is not an exception: the result has ``diverged = True``, the
    time and the signal, and the logged rows up to that point.

    Parameters
    ----------
    scenario : Scenario
        The validated scenario (``Scenario.read(...)``, ``Scenario.from_dict(...)``). Anything
        else is refused at once with a :class:`~imdrive.errors.ConfigError` naming what to
        use, rather than failing later inside the run.
    arrays : DriveArrays, optional
        The scenario's compiled records, if already built (``build_arrays(scenario)``).
    record : bool, optional
        Record what the controller saw every control period into ``result.recording``
        (:mod:`imdrive.run.recording`); None: as ``[output] recording`` says.

    Returns
    -------
    SimulationResult
        Signals (units in the column names), final states, status and timings.
    """
    if not isinstance(scenario, Scenario):
        raise ConfigError(
            "scenario",
            f"simulate() needs a Scenario, got {type(scenario).__name__} (use "
            "Scenario.read('preset or file.toml') or Scenario.from_dict(table))",
        )
    if arrays is not None and not isinstance(arrays, DriveArrays):
        raise ConfigError(
            "arrays",
            f"must be the scenario's DriveArrays (build_arrays(scenario)) or None, got "
            f"{type(arrays).__name__}",
        )
    a = arrays if arrays is not None else build_arrays(scenario)
    n_rows = a.n_steps // a.log_every + 1
    log = new_log(n_rows, a.log)
    state = copy_state(a.state0)
    if record is None:
        record = bool(scenario.output.recording)
    # an array either way (zero-length when not recording: the engine records only below its
    # length), so a recording run and a plain one share one compiled engine; with None the
    # recording was a signature of its own, a whole engine compiled again per estimator
    rec = np.zeros(a.n_steps + 1 if record else 0, dtype=RECORDING)
    # a zero-length call loads (or compiles) the kernel, so wall_time_s measures the run alone;
    # on a cold cache a second process compiles the loop's late blocks meanwhile
    t0 = time.perf_counter()
    first = prefetch.engine_call(a.params, copy_state(a.state0), log, rec)
    prefetch.start_loop(run_drive, first, a.params, a.state0, log)
    run_drive(*first)
    startup = time.perf_counter() - t0
    t0 = time.perf_counter()
    n_main = (a.n_steps // a.log_every) * a.log_every
    end_row = None
    if n_main == a.n_steps:
        status, k_end = run_drive(a.params, state, 0, a.n_steps, log, a.log_every, 0, True, rec)
    else:
        # the last logged row is before t_end: run the rest in a second call (consecutive calls
        # reproduce one long call exactly), which logs the row at n_main (the one the first
        # call, without its closing sample, left out) and the state at t_end
        status, k_end = run_drive(a.params, state, 0, n_main, log, a.log_every, 0, False, rec)
        if status == S_OK:
            tail = new_log(2, a.log)
            rest = a.n_steps - n_main
            rec_rest = rec[n_main:]
            status, k_rest = run_drive(a.params, state, 0, rest, tail, rest, n_main, True, rec_rest)
            log[-1] = tail[0]
            k_end = n_main + k_rest
            if status == S_OK:
                end_row = tail[1:2]
    wall = time.perf_counter() - t0
    log = logged_rows(log, status, k_end, a.log_every)
    res = SimulationResult.from_log(
        scenario,
        log,
        a.state0,
        state,
        a.params,
        int(status),
        int(k_end),
        wall,
        a.derived,
        a.log_units,
    )
    if end_row is not None:
        res.end_values = {
            k: float(v[0])
            for k, v in columns_from_log(end_row, res.vector, res.extra_units).items()
        }
    res.startup_s = startup
    if record:
        from imdrive.run.recording import recording_columns

        rows = rec[: k_end + 1 if status == S_OK else k_end]
        vdc_meas = float(a.params.sensor[0]["vdc_gain"] * a.params.inverter[0]["Vdc"])
        res.recording = recording_columns(rows, float(a.params.plant[0]["n_p"]), vdc_meas)
    return res
