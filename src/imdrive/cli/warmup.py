"""``imdrive warm-up``: compile every kernel entry point into the cache, on every core.

Each compiled entry point is a job: the drive once per registered estimator (the engine is
specialised by the estimator's records) and, for the MRAS, once per set of optional blocks
(the engine is specialised by the blocks a drive runs too, kernels/features.py), the batch
kernel (sweeps, once per estimator: the same for the threads and for dask; ``batch:all``, the
one of a batch of several estimators, kernels/estimators/union.py), the replay once per
estimator (the estimator and its R2 law on a recording) and the stability map's. The first
job compiles the MRAS drive, which the other entry points of the same blocks link in; the
others then run in parallel processes (numba compiles one function at a time per process).
A job whose kernels are cached takes the time to load them (about 1 s).

The test suite runs it before its workers start (``tests/conftest.py``), so that two workers do
not compile the same kernel side by side.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from imdrive.cli._common import EXIT_INTERNAL, EXIT_OK, _examples
from imdrive.errors import ConfigError

#: The short run every job compiles with, s (a few control periods).
T_END_S = 0.002


#: The optional blocks a drive compiles (kernels/features.py ``GROUPS``), each set as a preset
#: that runs it: the MRAS drive is compiled with each (``drive:mras:<set>``), its batch kernel
#: with the two a sweep most often runs (``batch:mras:<set>``; in the test suite two workers
#: compiled each side by side, 15-17 s apiece).
FEATURE_SETS = {
    "r2": "injection-robust",
    "realistic": "sensorless-realistic",
    "r2+realistic": "injection-fig5-realistic",
}


def jobs() -> list[str]:
    """Every job name, the MRAS drive first: ``drive:<estimator>``, ``drive:mras:<set>`` (the
    MRAS drive with each set of optional blocks, :data:`FEATURE_SETS`), ``batch`` (the MRAS's),
    ``batch:mras:<set>``, ``batch:<estimator>``, ``batch:all`` (every estimator in one batch:
    their union's kernel), ``replay:<estimator>``, ``stability``.
    (``batch-serial`` is still accepted: since 2026-11-30 it compiles what ``batch`` does.)"""
    from imdrive.run.estimators import estimator_names

    names = [n for n in estimator_names() if n != "mras"]
    replayed = [n for n in estimator_names() if n != "measured"]
    return [
        "drive:mras",
        *(f"drive:mras:{s}" for s in FEATURE_SETS),
        *(f"drive:{n}" for n in names),
        "batch",
        *(f"batch:mras:{s}" for s in ("r2", "realistic")),
        *(f"batch:{n}" for n in names if n != "measured"),
        "batch:all",
        *(f"replay:{n}" for n in replayed),
        "stability",
    ]


def _scenario(estimator: str = "mras", preset: str = "sensorless"):
    from imdrive.config.scenario import Scenario

    return Scenario.read(
        preset, [f'control.speed_feedback="{estimator}"', f"simulation.t_end_s={T_END_S}"]
    )


def run_job(name: str) -> None:
    """Compile (or load) the kernels of job ``name`` in this process."""
    kind, _, estimator = name.partition(":")
    estimator, _, blocks = estimator.partition(":")
    if blocks and blocks not in FEATURE_SETS:
        raise ConfigError("job", f"unknown job {name!r} (known: {', '.join(jobs())})")
    if kind == "drive":
        from imdrive.run.simulate import simulate

        simulate(_scenario(estimator, FEATURE_SETS.get(blocks, "sensorless")))
    elif kind in ("batch", "batch-serial"):
        from imdrive.run.batch import simulate_batch

        if estimator == "all":
            from imdrive.run.estimators import estimator_names

            scs = [_scenario(n) for n in estimator_names() if n != "measured"]
        else:
            scs = [_scenario(estimator or "mras", FEATURE_SETS.get(blocks, "sensorless"))] * 2
        simulate_batch(scs, parallel=kind == "batch")
    elif kind == "replay":
        import tempfile

        from imdrive.run.replay import replay
        from imdrive.run.simulate import simulate

        with tempfile.TemporaryDirectory() as d:
            simulate(_scenario(estimator), record=True).save(f"{d}/run", formats=["recording"])
            replay(f"{d}/run", estimators=estimator)
    elif kind == "stability":
        from imdrive.stability.maps import stability_map

        stability_map(_scenario(), [500.0], [0.0])
    else:
        raise ConfigError("job", f"unknown job {name!r} (known: {', '.join(jobs())})")


def _spawn(name: str, alone: bool = True) -> tuple[str, float, str]:
    t0 = time.perf_counter()
    env = {**os.environ, "NUMBA_NUM_THREADS": os.environ.get("NUMBA_NUM_THREADS", "1")}
    if not alone:  # jobs side by side fill the cores: no cold-start helper each (run/prefetch.py)
        env["IMDRIVE_PREFETCH"] = "0"
    res = subprocess.run(
        [sys.executable, "-m", "imdrive", "warm-up", "--job", name],
        capture_output=True,
        text=True,
        # compiling is one thread's work; the jobs themselves are the parallelism
        env=env,
    )
    err = "" if res.returncode == 0 else (res.stderr.strip().splitlines() or ["?"])[-1]
    return name, time.perf_counter() - t0, err


def _stamp(names) -> Path:
    """The file that says these jobs' kernels are all cached (named by their cache keys)."""
    import hashlib

    from imdrive import _cache

    keys = _cache.module_keys()
    h = hashlib.sha256()
    for part in (*sorted(names), *(keys[f"imdrive.kernels.{m}"] for m in _STAMPED)):
        h.update(part.encode() + b"\0")
    return _cache.cache_root() / f"warm-{h.hexdigest()[:16]}.done"


#: The kernel modules whose keys cover every job's entry point (each imports the engine).
_STAMPED = ("engine", "batch", "linearise", "replay")


def warm_up(names=None, processes: int | None = None, log=None) -> dict[str, float]:
    """Compile the kernels of ``names`` (default: every job), in parallel processes.

    Parameters
    ----------
    names : sequence of str, optional
        Jobs (:func:`jobs`); ``drive:mras`` runs first if present.
    processes : int, optional
        Parallel processes after the first job (default: the CPUs).
    log : callable, optional
        Called with a line per job.

    Returns
    -------
    dict of str to float
        Wall time of each job, s; empty if an earlier warm-up of the same jobs and the same
        kernels completed (a stamp file in the cache root).

    Raises
    ------
    RuntimeError
        If a job failed (its last line of stderr).
    """
    names = list(jobs() if names is None else names)
    stamp = _stamp(names)
    if stamp.exists():
        if log:
            log("  every job's kernels are cached already")
        return {}
    processes = processes or os.cpu_count() or 1
    first = [n for n in names if n == "drive:mras"]
    rest = [n for n in names if n != "drive:mras"]
    times, failed = {}, []
    for batch in (first, rest):
        with ThreadPoolExecutor(max(1, min(processes, len(batch) or 1))) as pool:
            alone = len(batch) == 1 or processes == 1
            for name, dt, err in pool.map(lambda n, a=alone: _spawn(n, a), batch):
                times[name] = dt
                if err:
                    failed.append(f"{name}: {err}")
                if log:
                    log(f"  {name:<24} {dt:6.1f} s{'  FAILED: ' + err if err else ''}")
    if failed:
        raise RuntimeError("; ".join(failed))
    stamp.touch()
    return times


def _cmd_warm_up(args) -> int:
    if args.job:
        run_job(args.job)
        return EXIT_OK
    names = None
    if args.only:
        names = [n.strip() for n in args.only.split(",") if n.strip()]
        unknown = sorted(set(names) - set(jobs()) - {"batch-serial"})  # batch's, still accepted
        if unknown:
            raise ConfigError("--only", f"unknown job {unknown[0]!r} (known: {', '.join(jobs())})")
    if args.processes is not None and args.processes < 1:
        raise ConfigError("--processes", f"must be at least 1, got {args.processes}")
    t0 = time.perf_counter()
    log = None if args.quiet else (lambda line: print(line, file=sys.stderr))
    if log:
        log("imdrive: compiling every kernel entry point (a job each; cached ones load in ~1 s)")
    try:
        warm_up(names, args.processes, log)
    except RuntimeError as exc:
        print(f"imdrive: error: warm-up failed: {exc}", file=sys.stderr)
        return EXIT_INTERNAL
    if log:
        log(f"imdrive: kernels ready in {time.perf_counter() - t0:.1f} s")
    return EXIT_OK


def add_parser(sub) -> None:
    """Register ``imdrive warm-up``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``imdrive`` parser's sub-commands.
    """
    p = sub.add_parser(
        "warm-up",
        help="compile every kernel into the cache, in parallel processes",
        description="Compile every kernel entry point (the drive for each estimator, the batch "
        "and stability kernels) into the cache, the MRAS drive first, then the rest in parallel "
        "processes. Optional: any command compiles what it needs on first use.",
        epilog=_examples("imdrive warm-up", "imdrive warm-up --only drive:mras,batch"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--only", metavar="JOBS", help="comma-separated jobs (default: all)")
    p.add_argument("--processes", type=int, metavar="N", help="parallel processes (default: CPUs)")
    p.add_argument("--job", help=argparse.SUPPRESS)  # one job, in this process (the workers)
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing")
    p.set_defaults(func=_cmd_warm_up)


__all__ = ["add_parser", "jobs", "run_job", "warm_up"]
