"""Wall time of the published commands: ``imdrive paper`` and ``imdrive sweep detuning-map``.

Run from the repository root with imdrive installed::

    python benchmarks/bench_commands.py [--repeat N] [--only paper|sweep] [--json PATH]

Each command runs once untimed (so the numba cache is warm: compiling is a first-run cost,
timed by ``bench_engine.py``), then ``--repeat`` times (default 3) in a subprocess, each into a
fresh temporary folder. For each run it records the wall time, the CPU time of the command
(user + system, all threads; the sweep runs on every core) and the 1-minute load average just
before it. The figures are printed as ranges with the machine and the date: on a shared machine
the same command varies by a factor of two with what else runs.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _measured import machine_line, span

COMMANDS = {
    "paper": ["paper"],
    "sweep": ["sweep", "detuning-map", "-q"],
}
LABELS = {
    "paper": "imdrive paper (every figure and table of the reproduction)",
    "sweep": "imdrive sweep detuning-map (567 drives of 14 s, heatmaps, report)",
}


def _children_cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def time_command(args: list[str], repeat: int) -> dict:
    """Wall and CPU time of ``imdrive ARGS --out TMP`` over ``repeat`` runs after a warm-up."""
    walls, cpus, loads = [], [], []
    for k in range(repeat + 1):
        with tempfile.TemporaryDirectory(prefix="imdrive-bench-") as tmp:
            cmd = [sys.executable, "-m", "imdrive", *args, "--out", str(Path(tmp) / "out")]
            load = os.getloadavg()[0]
            c0, t0 = _children_cpu_s(), time.perf_counter()
            proc = subprocess.run(cmd, capture_output=True, text=True)
            wall, cpu = time.perf_counter() - t0, _children_cpu_s() - c0
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr}")
        if k:  # the first run warms the numba cache
            walls.append(wall)
            cpus.append(cpu)
            loads.append(load)
    return {"wall_s": walls, "cpu_s": cpus, "load_avg_1min": loads}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="timed runs of each command")
    ap.add_argument("--only", choices=sorted(COMMANDS), help="time one command")
    ap.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    args = ap.parse_args(argv)
    print(machine_line())
    results = {}
    for name, cmd in COMMANDS.items():
        if args.only and name != args.only:
            continue
        r = results[name] = time_command(cmd, args.repeat)
        loads = r["load_avg_1min"]
        print(f"  {LABELS[name]}")
        print(f"    wall {span(r['wall_s'], digits=1)}")
        print(
            f"    CPU  {span(r['cpu_s'], digits=1)}, load average {min(loads):.1f}–{max(loads):.1f}"
        )
    if args.json:
        Path(args.json).write_text(json.dumps({"machine": machine_line(), **results}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
