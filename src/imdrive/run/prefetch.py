"""A cold start on two cores: a second process compiles the drive loop's late blocks while
this one compiles the loop.

A cold ``imdrive run`` spends nearly all its time compiling, on one core: numba types the loop
and compiles each block the loop calls when it meets the call. When the drive's loop is
neither compiled in this process nor cached (:func:`start`), a helper process
(:data:`HELPER`) compiles the blocks the loop's stages call last
(:func:`imdrive.kernels.prefetch.late_blocks`) into the same cache; this process, reaching
them, loads them from there. A block the helper has not finished is compiled here as before
(the cache's saves are locked, :func:`imdrive._cache._lock_index_saves`), so the helper can
only save time. Measured (2026-12-01, 2 cores, ``farm-bench``, runs paired with the helper
off, medians): a cold ``imdrive run sensorless`` 9.3 s against 12.9 s (5 pairs; ratio 0.76),
``paper-fig5`` 14.3 against 19.3 s, ``sensorless-realistic`` 12.7 against 19.3 s (2 runs
each); a warm run is unchanged (1.23 against 1.26 s, 10 pairs: the check is one read of the
loop's cache index). Off with ``IMDRIVE_PREFETCH=0``, and on a single core.
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

#: The helper: ``python -c HELPER FILE`` compiles
#: :func:`~imdrive.kernels.prefetch.late_blocks` for the records pickled in ``FILE`` (removed
#: once read). It imports the kernels alone (not this package's ``run`` layer: 0.6 s).
HELPER = (
    "import pickle, sys; from pathlib import Path; path = Path(sys.argv[1]); "
    "P, S, log = pickle.loads(path.read_bytes()); path.unlink(missing_ok=True); "
    "from numba import typeof; from imdrive.kernels.prefetch import late_blocks; "
    "late_blocks.compile((typeof(P), typeof(S), typeof(log)))"
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


def start(engine, args, P, S, log) -> subprocess.Popen | None:
    """Start the helper if ``engine`` (the drive loop) must compile for ``args``.

    Parameters
    ----------
    engine : numba dispatcher
        :func:`imdrive.kernels.engine.run_drive`.
    args : tuple
        The arguments of its first call.
    P, S, log : DriveParams, DriveState, numpy.ndarray
        The drive's records and its log (their types are what the helper compiles for).

    Returns
    -------
    subprocess.Popen or None
        The helper, or None if none was started.
    """
    if os.environ.get(ENV, "1") == "0" or _cores() < 2:
        return None
    if _compiled_or_cached(engine, args):
        return None
    from imdrive._cache import cache_root

    path = None
    try:
        with tempfile.NamedTemporaryFile(
            dir=cache_root(), prefix="prefetch-", suffix=".pkl", delete=False
        ) as f:  # a name of its own: one process may start several helpers
            path = Path(f.name)
            pickle.dump((P, S, log[:1]), f, protocol=pickle.HIGHEST_PROTOCOL)
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
