"""Kernel speed of two source trees of imdrive, alternated in one run, per preset.

Run from the repository root with the imdrive venv::

    python benchmarks/bench_trees.py OLD_REV [--new NEW_REV] [--repeat N] [--rounds R]
        [--presets a,b,...] [--interleaved N]

``OLD_REV`` and ``NEW_REV`` (default ``HEAD``) are git revisions (e.g. ``HEAD~3``, a tag);
each is checked out into a temporary worktree, so edits made while it runs do not count.
Each round runs, for each preset, one subprocess per tree (old, new, then new, old in the
next round, so drift of the machine's load falls on both): the subprocess imports
imdrive from that tree's ``src`` (``PYTHONPATH``), compiles or loads the kernel, then times
``--repeat`` runs of ``run_drive`` over the whole preset in process CPU time (robust on a
shared machine). Prints, per preset, each tree's range (lowest-highest, median, runs) and
three ratios new/old (below 1: the new tree is faster): of the medians of all runs; of the
fastest runs (the least disturbed by other jobs); and the paired ratios of each round (the
median of the new tree's runs over the old tree's, the two subprocesses run back to back),
as their range and median: on a loaded machine the paired and fastest-run ratios are the
ones to read, the median of all runs mixes rounds of different load.

``--interleaved N`` times the trees another way, for differences of a few per cent on a
shared machine: per preset, one live subprocess per tree (kernel compiled or loaded once),
and N runs of each alternated one run at a time (old, new, then new, old), so both trees see
the same load within a fraction of a second; prints each tree's range and the run-by-run
ratios new/old (median and quartiles).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _measured import machine_line, span

ROOT = Path(__file__).resolve().parents[1]
PRESETS = (
    "free-acceleration",
    "sensorless",
    "paper-fig5",
    "injection-fig5",
    "vector-sensored",
    "sensorless-realistic",
)

_CHILD = r"""
import json, sys, time
from imdrive.config.scenario import Scenario
from imdrive.kernels.engine import run_drive
from imdrive.run.build import build_arrays, copy_state
import importlib

_s = importlib.import_module("imdrive.run.simulate")

preset, repeat = sys.argv[1], int(sys.argv[2])
sc = Scenario.read(preset)
a = build_arrays(sc)
n_rows = a.n_steps // a.log_every + 1
# a tree whose drive carries its log dtype, or one with a single log dtype
log = _s.new_log(n_rows, a.log) if hasattr(a, "log") else _s.new_log(n_rows)
run_drive(a.params, copy_state(a.state0), 0, 1, log, a.log_every)  # compile or load
times = []
for _ in range(repeat):
    S = copy_state(a.state0)
    t0 = time.process_time()
    run_drive(a.params, S, 0, a.n_steps, log, a.log_every)
    times.append(time.process_time() - t0)
print(json.dumps({"periods": int(a.n_steps), "times": times}))
"""


_LIVE_CHILD = r"""
import sys, time
from imdrive.config.scenario import Scenario
from imdrive.kernels.engine import run_drive
from imdrive.run.build import build_arrays, copy_state
import importlib

_s = importlib.import_module("imdrive.run.simulate")
a = build_arrays(Scenario.read(sys.argv[1]))
n_rows = a.n_steps // a.log_every + 1
log = _s.new_log(n_rows, a.log) if hasattr(a, "log") else _s.new_log(n_rows)
run_drive(a.params, copy_state(a.state0), 0, 1, log, a.log_every)  # compile or load
print(a.n_steps, flush=True)
for _ in sys.stdin:  # one timed run per line
    S = copy_state(a.state0)
    t0 = time.process_time()
    run_drive(a.params, S, 0, a.n_steps, log, a.log_every)
    print(time.process_time() - t0, flush=True)
"""


def _interleaved(trees: dict[str, Path], preset: str, n: int) -> dict[str, list[float]]:
    """``n`` runs of ``preset`` in each tree, alternated one run at a time between two live
    subprocesses (old, new, then new, old): us per period, per tree."""
    procs = {}
    for tree, src in trees.items():
        env = dict(os.environ, PYTHONPATH=str(src), NUMBA_NUM_THREADS="1")
        procs[tree] = subprocess.Popen(
            [sys.executable, "-c", _LIVE_CHILD, preset],
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
    try:
        periods = {tree: int(proc.stdout.readline()) for tree, proc in procs.items()}
        us: dict[str, list[float]] = {tree: [] for tree in trees}
        for r in range(n):
            for tree in ("old", "new") if r % 2 == 0 else ("new", "old"):
                procs[tree].stdin.write("\n")
                procs[tree].stdin.flush()
                us[tree].append(float(procs[tree].stdout.readline()) / periods[tree] * 1e6)
    finally:
        for proc in procs.values():
            proc.stdin.close()
            proc.wait()
    return us


def _print_interleaved(presets: list[str], us: dict[str, dict[str, list[float]]], old, new):
    print(f"\nkernel CPU time per control period, us, runs interleaved (old = {old}, new = {new})")
    print(f"{'preset':22s} {'old':40s} {'new':40s} new/old run by run: median (quartiles)")
    for p in presets:
        o, n = us[p]["old"], us[p]["new"]
        q = statistics.quantiles([b / a for a, b in zip(o, n, strict=True)], n=4)
        print(
            f"{p:22s} {span(o, 'us', digits=3):40s} {span(n, 'us', digits=3):40s} "
            f"{q[1]:.4f} ({q[0]:.4f}-{q[2]:.4f})"
        )


def _run(src: Path, preset: str, repeat: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src), NUMBA_NUM_THREADS="1")
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, preset, str(repeat)],
        env=env,
        capture_output=True,
        text=True,
    )
    if out.returncode != 0:
        raise SystemExit(f"{src}: {preset} failed:\n{out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old_rev")
    ap.add_argument("--new", default="HEAD", help="the new revision (default HEAD)")
    ap.add_argument("--repeat", type=int, default=5, help="timed runs per subprocess")
    ap.add_argument("--rounds", type=int, default=2, help="alternations old/new")
    ap.add_argument("--presets", default=",".join(PRESETS))
    ap.add_argument("--json", help="write the raw times here")
    ap.add_argument(
        "--interleaved", type=int, default=0, metavar="N",
        help="instead: N runs per tree alternated run by run between two live subprocesses",
    )  # fmt: skip
    args = ap.parse_args(argv)
    print(machine_line())
    presets = [p for p in args.presets.split(",") if p]
    with tempfile.TemporaryDirectory() as tmp:
        revs = {"old": args.old_rev, "new": args.new}
        for tree, rev in revs.items():
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", f"{tmp}/{tree}", rev],
                check=True,
            )
        try:
            trees = {tree: Path(tmp) / tree / "src" for tree in revs}
            if args.interleaved:
                us = {p: _interleaved(trees, p, args.interleaved) for p in presets}
                _print_interleaved(presets, us, args.old_rev, args.new)
                if args.json:
                    Path(args.json).write_text(json.dumps({"interleaved_us": us}, indent=1))
                return 0
            times: dict[str, dict[str, list[float]]] = {p: {"old": [], "new": []} for p in presets}
            paired: dict[str, list[float]] = {p: [] for p in presets}
            periods = {}
            for r in range(args.rounds):
                order = ("old", "new") if r % 2 == 0 else ("new", "old")
                for p in presets:
                    med = {}
                    for tree in order:
                        res = _run(trees[tree], p, args.repeat)
                        periods[p] = res["periods"]
                        us = [t / res["periods"] * 1e6 for t in res["times"]]
                        times[p][tree] += us
                        med[tree] = statistics.median(us)
                    paired[p].append(med["new"] / med["old"])
        finally:
            for tree in revs:
                subprocess.run(
                    ["git", "-C", str(ROOT), "worktree", "remove", "--force", f"{tmp}/{tree}"],
                    check=False,
                )
    print(f"\nkernel CPU time per control period, us (old = {args.old_rev}, new = {args.new})")
    print(f"{'preset':22s} {'old':40s} {'new':40s} new/old: medians, fastest, paired rounds")
    for p in presets:
        o, n = times[p]["old"], times[p]["new"]
        ratio = statistics.median(n) / statistics.median(o)
        fastest = min(n) / min(o)
        pr = span(paired[p], "", digits=3)
        print(
            f"{p:22s} {span(o, 'us', digits=3):40s} {span(n, 'us', digits=3):40s} "
            f"{ratio:.3f}, {fastest:.3f}, {pr}"
        )
    if args.json:
        Path(args.json).write_text(
            json.dumps({"periods": periods, "times_us": times, "paired": paired}, indent=1)
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
