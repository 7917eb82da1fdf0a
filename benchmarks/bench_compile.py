"""Where a cold start's time goes: each compiled function's share, and the command as a whole.

Runs an imdrive command in a fresh process with an empty kernel cache (a temporary
``IMDRIVE_CACHE_DIR``; with ``--warm-first CMD``, that command runs first in the same cache, so
the figures are of what the second command adds), and listens to numba's ``numba:compile``
events there: for every compiled function, its time including what it compiled inside it, and
its own time (the rest). Prints the command's wall time, the compile total and a table of the
functions with the largest own time.

    python benchmarks/bench_compile.py                          # imdrive run sensorless, cold
    python benchmarks/bench_compile.py --repeat 3 --top 25
    python benchmarks/bench_compile.py --warm-first "run sensorless" --cmd "stability sensorless"
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _measured import machine_line, span

PROBE = r"""
import json, sys, time
from numba.core import event

rows, stack = [], []

class Listener(event.Listener):
    def on_start(self, ev):
        f = getattr(ev.data.get("dispatcher"), "py_func", None)
        name = f"{getattr(f, '__module__', '?')}.{getattr(f, '__qualname__', '?')}"
        stack.append([name, time.perf_counter(), 0.0])

    def on_end(self, ev):
        name, t0, inner = stack.pop()
        dt = time.perf_counter() - t0
        if stack:
            stack[-1][2] += dt
        rows.append((name, len(stack), dt, dt - inner))

event.register("numba:compile", Listener())
from imdrive.cli import main
t0 = time.perf_counter()
try:
    code = main(sys.argv[2:])
except SystemExit as e:
    code = e.code
wall = time.perf_counter() - t0
json.dump({"code": code, "wall": wall, "rows": rows}, open(sys.argv[1], "w"))
"""


def _run(cmd: list[str], cache: str, out: str) -> dict:
    env = {**os.environ, "IMDRIVE_CACHE_DIR": cache}
    env.pop("NUMBA_CACHE_DIR", None)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", PROBE, out, *cmd], env=env, check=True)
    res = json.loads(Path(out).read_text())
    res["process"] = time.perf_counter() - t0
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cmd", default="run sensorless -q", help="imdrive arguments")
    ap.add_argument("--warm-first", default="", help="imdrive arguments run first, same cache")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--top", type=int, default=20)
    args = ap.parse_args()
    print(machine_line())
    totals, walls, own = [], [], {}
    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory() as tmp:
            cache, res_file = str(Path(tmp) / "cache"), str(Path(tmp) / "r.json")
            out = ["--out", str(Path(tmp) / "out")] if args.cmd.split()[0] != "warm-up" else []
            if args.warm_first:
                warm = shlex.split(args.warm_first)
                _run([*warm, "--out", str(Path(tmp) / "w")], cache, res_file)
            res = _run([*shlex.split(args.cmd), *out], cache, res_file)
        walls.append(res["process"])
        totals.append(sum(r[2] for r in res["rows"] if r[1] == 0))
        for name, _, _, self_s in res["rows"]:
            own.setdefault(name, []).append(self_s)
    print(f"imdrive {args.cmd}" + (f" after {args.warm_first}" if args.warm_first else ""))
    print(f"  whole process: {span(walls)}")
    print(f"  compilation:   {span(totals)}")
    n = args.repeat
    ranked = sorted(own.items(), key=lambda kv: -sum(kv[1]) / n)
    print(f"\n| function | own compile time, s (mean of {n}) | share |")
    print("|---|---|---|")
    total = sum(totals) / n
    for name, vals in ranked[: args.top]:
        mean = sum(vals) / n
        print(f"| `{name}` | {mean:.2f} | {100 * mean / total:.0f} % |")
    rest = sum(sum(v) / n for _, v in ranked[args.top :])
    print(f"| {len(ranked) - args.top} others | {rest:.2f} | {100 * rest / total:.0f} % |")


if __name__ == "__main__":
    main()
