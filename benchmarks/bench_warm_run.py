"""A warm ``imdrive run``: the whole command, and where its time goes outside the simulation.

The kernels are cached (the first run compiles them, uncounted). Each counted run is a fresh
process (``python -m imdrive run sensorless --out TMP -q`` by default), timed from outside:
wall time, and its CPU time from the operating system (``os.wait4``), which varies less than
wall time on a shared machine. With ``--tree`` given twice, the two source trees (``src/``
folders) run in turn, A B A B ..., and the ratio A/B is taken run by run, so a machine whose
speed drifts during the measurement still gives a fair ratio.

``--phases`` prints, for the first tree, one in-process run split into phases: importing imdrive
(the configuration layer, pydantic), numba and the kernels, reading the scenario, the first call
of the kernel (numba loads its typing registries, imports scipy.linalg, and reads the cached
machine code), the simulation, and writing the results.

    python benchmarks/bench_warm_run.py                       # this tree, 7 runs
    python benchmarks/bench_warm_run.py --tree src --tree ../main/src --repeat 9
    python benchmarks/bench_warm_run.py --phases --args "run sensorless --format csv,report,figures"
"""

from __future__ import annotations

import argparse
import os
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _measured import machine_line, span

PHASES = r"""
import sys, time
t = [time.perf_counter()]
rows = []
def lap(name):
    now = time.perf_counter(); rows.append((name, now - t[0])); t[0] = now
import imdrive.config.scenario; lap("import imdrive (configuration, pydantic, numpy)")
import numba; lap("import numba")
import imdrive.kernels, imdrive.run.simulate, imdrive.cli; lap("import the kernels, run, cli")
from imdrive.config.scenario import Scenario
from imdrive.run.build import build_arrays
sc = Scenario.read(sys.argv[1], []); arrays = build_arrays(sc); lap("read the scenario, build")
from imdrive.run.simulate import simulate
res = simulate(sc, arrays, record=False)
lap("simulate: load the cached kernel + run")
res.summary(); res.save(sys.argv[2], force=True); lap("summary, save (default outputs)")
print(f"kernel (res.wall_time_s): {res.wall_time_s:.3f} s")
for name, s in rows:
    print(f"{name:50s} {s:6.3f} s")
print(f"{'all':50s} {sum(s for _, s in rows):6.3f} s")
"""


def _one(src: str, args: list[str], out: str) -> tuple[float, float]:
    env = {**os.environ, "PYTHONPATH": src}
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "imdrive", *args, "--out", out],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    err = proc.stderr.read().decode() if proc.stderr else ""
    proc.stderr.close()
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{src}: imdrive {' '.join(args)} failed: {err.strip()[-300:]}")
    return wall, usage.ru_utime + usage.ru_stime


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tree", action="append", help="a src/ folder (give two to compare)")
    ap.add_argument("--args", default="run sensorless -q", help="the imdrive command's arguments")
    ap.add_argument("--repeat", type=int, default=7, help="counted runs per tree")
    ap.add_argument("--phases", action="store_true", help="also split one run into phases")
    a = ap.parse_args(argv)
    trees = [str(Path(t).resolve()) for t in (a.tree or [Path(__file__).parents[1] / "src"])]
    args = shlex.split(a.args)
    print(machine_line())
    with tempfile.TemporaryDirectory() as tmp:
        for i, src in enumerate(trees):  # compiles what is not cached; not counted
            _one(src, args, f"{tmp}/warm-{i}")
        times = {src: [] for src in trees}
        for _ in range(a.repeat):
            for i, src in enumerate(trees):
                times[src].append(_one(src, args, f"{tmp}/run-{i}"))
        for i, src in enumerate(trees):
            wall = [w for w, _ in times[src]]
            cpu = [c for _, c in times[src]]
            print(f"{'AB'[i] if len(trees) > 1 else ''} {src}: imdrive {a.args}")
            print(f"  wall {span(wall)}; CPU {span(cpu)}")
        if len(trees) == 2:
            (a_, b_) = (times[t] for t in trees)
            for k, what in ((0, "wall"), (1, "CPU")):
                r = [x[k] / y[k] for x, y in zip(a_, b_, strict=True)]
                med = statistics.median(r)
                print(f"  A/B {what}: median {med:.3f} ({min(r):.3f}-{max(r):.3f})")
        if a.phases:
            subprocess.run(
                [sys.executable, "-c", PHASES, args[1], f"{tmp}/phases"],
                env={**os.environ, "PYTHONPATH": trees[0]},
                check=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
