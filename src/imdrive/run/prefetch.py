"""Cold starts on two cores: a second process compiles what this one will need later.

A cold ``imdrive run`` spends nearly all its time compiling, on one core: numba types the loop
and compiles each block the loop calls when it meets the call. When the drive's loop is neither
compiled in this process nor cached (:func:`start_loop`), a helper process (:data:`HELPER`)
compiles the blocks the loop's stages call last (:func:`imdrive.kernels.prefetch.late_blocks`)
into the same cache; this process, reaching them, loads them from there. A batch whose drives
need several kernels not yet compiled (one per R2 law and decimation of the log; drives that
differ by estimator share one, :mod:`imdrive.kernels.estimators.union`) has the helper compile
them from the last while it compiles and runs them from the first (:func:`start_batch`); a
batch with one such kernel (a first sweep of the realistic drive, a first ``imdrive
bench-estimators``) has it compile that kernel's late blocks, as for a drive: a
first four-drive sweep of ``sensorless-realistic`` after a warm ``run sensorless`` took 11.1
and 11.3 s against 13.7 and 14.2 s (2 alternated pairs, 2026-12-02; warm 1.9-2.0 s). What the
helper has not finished is compiled here as before (the cache's saves are locked,
:func:`imdrive._cache._lock_index_saves`), so the helper can only save time. Measured
(2026-12-01, 2 cores, ``farm-bench``, runs paired with the helper off, medians): a cold
``imdrive run sensorless`` 9.3 s against 12.9 s (5 pairs; ratio 0.76), ``paper-fig5`` 14.3
against 19.3 s, ``sensorless-realistic`` 12.7 against 19.3 s (2 runs each); a warm run is
unchanged (1.23 against 1.26 s, 10 pairs: the check is one read of the loop's cache index). The
first ``imdrive bench-estimators`` after a warm ``run sensorless``, when it compiled 5 kernels,
one per estimator's records: 42.9 and 45.8 s against 66.3 and 69.8 s (2 runs each; warm
11.5-13.2 s). Off with ``IMDRIVE_PREFETCH=0``, and on a single core.
"""

from __future__ import annotations

import atexit
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

#: The environment variable that turns the helper off (``0``).
ENV = "IMDRIVE_PREFETCH"

#: The helper: ``python -c HELPER FILE`` compiles, in their order, the jobs pickled in ``FILE``
#: (removed once read): ``(module, function, args)``, the compiled function of that module for
#: the types of ``args``. It imports the kernels alone (not this package's ``run`` layer: 0.6 s).
HELPER = (
    "import importlib, pickle, sys; from pathlib import Path; path = Path(sys.argv[1]); "
    "jobs = pickle.loads(path.read_bytes()); path.unlink(missing_ok=True); "
    "from numba import typeof\n"
    "for module, name, args in jobs:\n"
    "    f = getattr(importlib.import_module(module), name)\n"
    "    f.compile(tuple(typeof(a) for a in args))"
)


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _compiled_or_cached(dispatcher, args) -> bool:
    """Whether ``dispatcher`` has ``args``' specialisation in this process or in its cache
    (True when numba's internals do not tell: then no helper)."""
    try:
        sig = tuple(dispatcher.typeof_pyval(a) for a in args)
        if sig in dispatcher.overloads:
            return True
        cache = dispatcher._cache
        key = cache._index_key(sig, dispatcher.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:  # numba's private API moved: behave as before the helper existed
        return True


def start(jobs, check: bool = True) -> subprocess.Popen | None:
    """Start a helper that compiles ``jobs``, a list of ``(dispatcher, args)``, in their order,
    into the cache; with ``check``, those already compiled or cached are left out.

    Returns
    -------
    subprocess.Popen or None
        The helper, or None if none was started (nothing to compile, one core, or turned off).
    """
    if os.environ.get(ENV, "1") == "0" or _cores() < 2:
        return None
    todo = [
        (d.py_func.__module__, d.py_func.__name__, args)
        for d, args in jobs
        if not (check and _compiled_or_cached(d, args))
    ]
    if not todo:
        return None
    from imdrive._cache import cache_root

    path = None
    try:
        with tempfile.NamedTemporaryFile(
            dir=cache_root(), prefix="prefetch-", suffix=".pkl", delete=False
        ) as f:  # a name of its own: one process may start several helpers
            path = Path(f.name)
            pickle.dump(todo, f, protocol=pickle.HIGHEST_PROTOCOL)
        proc = subprocess.Popen(
            [sys.executable, "-c", HELPER, str(path)],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except OSError:  # no process or no file: compile here alone, as before
        if path is not None:
            path.unlink(missing_ok=True)
        return None
    # reaped at exit if it has ended (no zombie left behind); if not, it ends on its own
    atexit.register(proc.poll)
    return proc


def start_loop(engine, args, P, S, log, then=()) -> subprocess.Popen | None:
    """Start the helper on the loop's late blocks if ``engine`` (the drive loop,
    :func:`imdrive.kernels.engine.run_drive`) must compile for ``args``, the arguments of its
    first call; ``P``, ``S``, ``log``: the drive's records and its log; ``then``: jobs of
    :func:`start` the helper takes after them."""
    if os.environ.get(ENV, "1") == "0" or _compiled_or_cached(engine, args):
        return None
    from imdrive.kernels.prefetch import late_blocks

    # late_blocks itself is not cached: it is what it calls that is
    return start([(late_blocks, (P, S, log[:1])), *then], check=False)


def engine_call(P, S, log, rec=None) -> tuple:
    """The arguments of the drive loop's zero-length first call
    (:func:`imdrive.kernels.engine.run_drive`) on records ``P``, ``S`` with a log of ``log``'s
    dtype and recording ``rec`` (default none): ``simulate()``'s call, whose types the batch
    worker's calls have too (:func:`imdrive.kernels.batch.run_one`)."""
    if rec is None:
        import numpy as np

        from imdrive.kernels.recording import RECORDING

        rec = np.zeros(0, dtype=RECORDING)
    return (P, S, 0, 0, log[:0], 1, 0, True, rec)


def start_batch(worker, calls) -> subprocess.Popen | None:
    """Start the helper on the batch ``worker``'s specialisations, ``calls`` (the arguments of
    each group's call, in the order the batch runs them: the group's records first, its
    scratch log last), from the last: this process compiles them from the first, and the
    two meet in the middle. When only one must compile, the helper takes its loop's late
    blocks instead if the loop must compile too, as for a single drive (:func:`start_loop`),
    then what the worker calls besides the loop (:func:`imdrive.kernels.batch.worker_blocks`:
    this process meets them after compiling the loop, the helper is idle by then)."""
    if os.environ.get(ENV, "1") == "0":
        return None
    todo = [args for args in calls if not _compiled_or_cached(worker, args)]
    if len(todo) == 1:
        from imdrive.kernels.batch import worker_blocks
        from imdrive.kernels.engine import run_drive

        P, S, scratch = todo[0][0], todo[0][1], todo[0][-1]
        then = [(worker_blocks, todo[0])]
        return start_loop(run_drive, engine_call(P, S, scratch), P, S, scratch, then)
    if len(todo) < 2:
        return None
    return start([(worker, args) for args in reversed(todo[1:])], check=False)
