"""Running a sweep: chunk by chunk, here with the batch engine or on a dask cluster.

:func:`run_sweep` opens and locks the store (:mod:`imdrive.sweep.store`), verifies the chunks
already there (a damaged one is removed and recomputed, with a notice), runs the chunks that
are missing, writes each as it completes, shows the progress, then consolidates the table,
draws the heatmaps (:mod:`imdrive.sweep.figures`) and only then marks the manifest complete.
A run's results do not depend on which chunk, process or machine computed it. A run that
cannot be built (a rule between axis values, a derived gain that overflows) is a row with
``status`` = -1 and its message in ``error``; the others go on.

Failures of the environment (a disk error, a dask cluster that loses its workers or its
scheduler) raise :class:`~imdrive.errors.EnvironmentFailure`: the chunks written so far stay,
the manifest does not say complete, and ``--resume`` continues.
"""

from __future__ import annotations

import sys
import uuid
from pathlib import Path

from imdrive._progress import Progress, _isatty
from imdrive.errors import ConfigError, EnvironmentFailure, check_argument
from imdrive.sweep.figures import save_heatmaps
from imdrive.sweep.scheduler import (  # noqa: F401  (check_scheduler_address: old path)
    CONNECT_TIMEOUT_S,
    check_scheduler_address,
    connect,
)
from imdrive.sweep.spec import Sweep, _int
from imdrive.sweep.store import lock_store, open_store


def _scenarios(sweep: Sweep, runs: range):
    """Each run's scenario, or a :class:`~imdrive.run.batch.FailedRun` saying why it has none."""
    from imdrive.run.batch import FailedRun

    for i in runs:
        try:
            yield sweep.scenario(i)
        except ConfigError as exc:
            yield FailedRun(str(exc))


def run_chunk(sweep: Sweep, j: int, chunk_size: int | None = None, parallel: bool = True):
    """Run chunk ``j`` of ``sweep``: its table (run, axis values, metrics), sorted by run.

    A run that cannot be built or whose derived parameters overflow is recorded as failed
    (``status`` -1, ``error``), the others go on.

    Parameters
    ----------
    sweep : Sweep
        The sweep.
    j : int
        Chunk index (runs ``j * chunk_size`` up to the next chunk).
    chunk_size : int, optional
        Runs per chunk; default the sweep's.
    parallel : bool
        Run the batch on all cores.

    Returns
    -------
    pandas.DataFrame
        One row per run: run index, axis values, metrics (units in the column names).
    """
    import pandas as pd

    from imdrive.run.batch import simulate_batch

    runs = sweep.chunk_runs(j, chunk_size)
    inputs = sweep.inputs(runs)
    res = simulate_batch(
        _scenarios(sweep, runs), window_s=sweep.window_s, parallel=parallel, errors="record"
    )
    met = res.metrics.drop(columns=["drive"])
    return pd.concat([inputs, met], axis=1)


def _dask_chunk(sweep: Sweep, j: int, chunk_size: int):
    """Task body on a dask worker: one thread, no GIL (the worker's own parallelism rules)."""
    return j, run_chunk(sweep, j, chunk_size, parallel=False)


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
    report: bool = True,
    notice=None,
    connect_timeout_s: float = CONNECT_TIMEOUT_S,
):
    """Run ``sweep`` into the store ``out``.

    Parameters
    ----------
    sweep : Sweep
        The sweep.
    out : str or pathlib.Path
        The store folder.
    scheduler : str, optional
        A dask.distributed scheduler address; without it (and without ``client``) chunks run
        here with the batch engine on all cores.
    resume : bool
        Continue an interrupted sweep in ``out``.
    chunk_size : int, optional
        Runs per chunk; default the sweep's.
    figures : bool
        Write the heatmap PNGs.
    progress : bool, optional
        None: a bar on stderr if it is a terminal, else one line saying what runs (through
        ``notice``).
    client : dask.distributed.Client, optional
        A connected client, in place of ``scheduler``.
    report : bool
        Write ``report.html``, the interactive heatmaps (:mod:`imdrive.sweep.report`).
    notice : callable, optional
        Receives that line and one per repaired chunk (default: printed on stderr).
    connect_timeout_s : float
        Seconds ``scheduler`` has to answer and greet as a dask scheduler (s); default 10.

    Returns
    -------
    pandas.DataFrame
        The consolidated table, one row per run, sorted by run.
    """
    import os

    check_argument(sweep, Sweep, "sweep", "a Sweep (load_sweep(...))")
    check_argument(out, (str, os.PathLike), "out", "a folder path (str or os.PathLike)")
    out = Path(out)
    if chunk_size is not None:
        chunk_size = _int(chunk_size, "--chunk-size")
    if notice is None:

        def notice(line):
            print(f"imdrive: {line}", file=sys.stderr)

    store, cs, started = open_store(sweep, out, resume, chunk_size)
    if client is None and scheduler is not None:
        client = connect(scheduler, connect_timeout_s)
        own_client = True
    else:
        own_client = False
    try:
        lock = lock_store(store)
    except BaseException:
        if own_client:
            client.close()
        raise
    try:
        return _run_locked(
            sweep, store, cs, started, client, own_client, figures, progress, notice, report
        )
    finally:
        lock.release()


def _run_locked(
    sweep, store, cs, started, client, own_client, figures, progress, notice, report=True
):
    """The body of :func:`run_sweep`, with the store's lock held."""
    store.clean_partials()
    for line in store.verify_chunks(sweep, cs):
        notice(line)
    store.write_source(sweep)
    store.write_manifest(sweep, cs, started)
    done = store.completed()
    pending = [j for j in range(sweep.n_chunks(cs)) if j not in done]
    if progress is None and not _isatty(sys.stderr):  # no bar will show: one line instead
        notice(
            f"sweep {sweep.name}: {sweep.n_runs} runs in {sweep.n_chunks(cs)} chunks of {cs} "
            f"({len(done)} done) -> {store.root}"
        )
    bar = Progress(sweep.n_runs, f"sweep {sweep.name}", unit="runs", enabled=progress)
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
            try:
                for fut in as_completed(futures, loop=client.loop):
                    j, df = fut.result()
                    store.write_chunk(j, df)
                    store.write_manifest(sweep, cs, started)
                    bar.advance(len(df))
            except (ConfigError, EnvironmentFailure, OSError, MemoryError):
                raise
            except Exception as exc:
                if not _from_dask(exc):
                    raise
                raise EnvironmentFailure(
                    f"the dask cluster failed ({type(exc).__name__}: "
                    f"{str(exc).splitlines()[0][:200] if str(exc) else 'no message'}); "
                    f"{len(store.completed())} of {sweep.n_chunks(cs)} chunks are in "
                    f"{store.root}: add --resume to continue"
                ) from None
    finally:
        bar.close()
        if own_client:
            try:
                client.close()
            except Exception:  # a cluster already gone: nothing to close
                pass
    # a chunk edited while the sweep ran (its sha256) is recomputed before the table is made,
    # and consolidate checks every checksum again as it reads
    for line in store.verify_chunks(sweep, cs):
        notice(line)
    for j in range(sweep.n_chunks(cs)):
        if j not in store.completed():
            store.write_chunk(j, run_chunk(sweep, j, cs))
            store.write_manifest(sweep, cs, started)
    df = store.consolidate(sweep, cs)
    if figures:
        save_heatmaps(sweep, df, store.root / "figures")
    if report:
        from imdrive.sweep.report import write_sweep_report

        write_sweep_report(sweep, df, store.root / "report.html")
    store.write_manifest(sweep, cs, started, complete=True)
    return df


def _from_dask(exc: BaseException) -> bool:
    """Whether an exception comes from dask/distributed (a lost worker, scheduler, comm)."""
    mod = type(exc).__module__ or ""
    return mod.split(".")[0] in ("distributed", "dask", "tornado", "asyncio") or isinstance(
        exc, TimeoutError
    )
