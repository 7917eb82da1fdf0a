"""Running a sweep: chunk by chunk, here with the batch engine or on a dask cluster.

:func:`run_sweep` opens the store (:mod:`imdrive.sweep.store`), runs the chunks that are
missing, writes each as it completes, shows the progress, then consolidates the table and draws
the heatmaps (:mod:`imdrive.sweep.figures`). A run's results do not depend on which chunk,
process or machine computed it.
"""

from __future__ import annotations

import uuid
from pathlib import Path

from imdrive._progress import Progress
from imdrive.errors import ConfigError
from imdrive.sweep.figures import save_heatmaps
from imdrive.sweep.spec import Sweep, _int
from imdrive.sweep.store import open_store


def run_chunk(sweep: Sweep, j: int, chunk_size: int | None = None, parallel: bool = True):
    """Run chunk ``j`` of ``sweep``: its table (run, axis values, metrics), sorted by run."""
    import pandas as pd

    from imdrive.run.batch import simulate_batch

    runs = sweep.chunk_runs(j, chunk_size)
    inputs = sweep.inputs(runs)
    res = simulate_batch(
        (sweep.scenario(i) for i in runs), window_s=sweep.window_s, parallel=parallel
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
):
    """Run ``sweep`` into the store ``out``; returns the consolidated table (pandas).

    ``scheduler`` is a dask.distributed scheduler address (or pass a ``client``); without
    either, chunks run here with the batch engine on all cores. ``progress`` None: a bar on
    stderr if it is a terminal.
    """
    out = Path(out)
    if chunk_size is not None:
        chunk_size = _int(chunk_size, "--chunk-size")
    store, cs, started = open_store(sweep, out, resume, chunk_size)
    if client is None and scheduler is not None:
        client = _connect(scheduler)
        own_client = True
    else:
        own_client = False
    store.chunks.mkdir(parents=True, exist_ok=True)
    store.clean_partials()
    store.write_source(sweep)
    store.write_manifest(sweep, cs, started)
    done = store.completed()
    pending = [j for j in range(sweep.n_chunks(cs)) if j not in done]
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
            for fut in as_completed(futures, loop=client.loop):
                j, df = fut.result()
                store.write_chunk(j, df)
                store.write_manifest(sweep, cs, started)
                bar.advance(len(df))
    finally:
        bar.close()
        if own_client:
            client.close()
    df = store.consolidate(sweep, cs)
    if figures:
        save_heatmaps(sweep, df, store.root / "figures")
    return df


def _connect(address: str):
    try:
        from dask.distributed import Client
    except ImportError:
        raise ConfigError(
            "--scheduler", "needs dask.distributed: pip install 'imdrive[dask]'"
        ) from None
    try:
        return Client(address, timeout="10s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ConfigError("--scheduler", f"cannot connect to {address}: {exc}") from None
