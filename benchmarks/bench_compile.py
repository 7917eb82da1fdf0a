"""Where a cold start's time goes: each compiled function's share, each compiler pass's, and
the command as a whole.

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

passes, pstack = {}, []

class Passes(event.Listener):  # each compiler pass's own time (nested compilations removed)
    def on_start(self, ev):
        pstack.append([ev.data["name"].split(" [")[0], time.perf_counter(), 0.0])

    def on_end(self, ev):
        name, t0, inner = pstack.pop()
        dt = time.perf_counter() - t0
        if pstack:
            pstack[-1][2] += dt
        passes[name] = passes.get(name, 0.0) + dt - inner

event.register("numba:run_pass", Passes())

from numba.core import codegen

llvm = {"s": 0.0}

def _timed(cls, name):  # LLVM's optimisation passes and machine-code generation
    f = getattr(cls, name)

    def g(self, *a, **k):
        t0 = time.perf_counter()
        try:
            return f(self, *a, **k)
        finally:
            llvm["s"] += time.perf_counter() - t0

    setattr(cls, name, g)

_timed(codegen.CPUCodeLibrary, "_optimize_functions")
_timed(codegen.CPUCodeLibrary, "_optimize_final_module")
_timed(codegen.JITCodeLibrary, "_finalize_specific")
from imdrive.cli import main
t0 = time.perf_counter()
try:
    code = main(sys.argv[2:])
except SystemExit as e:
    code = e.code
wall = time.perf_counter() - t0
json.dump({"code": code, "wall": wall, "rows": rows, "passes": passes,
           "llvm": llvm["s"]}, open(sys.argv[1], "w"))
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
    totals, walls, own, by_pass, llvm = [], [], {}, {}, []
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
        llvm.append(res.get("llvm", 0.0))
        for name, t in res.get("passes", {}).items():
            by_pass[name] = by_pass.get(name, 0.0) + t
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
    # by compiler stage: numba's own passes in Python (typing, rewrites) against the lowering,
    # which holds LLVM's optimisation and code generation
    print(f"\n| numba pass (all functions) | own time, s (mean of {n}) | share |")
    print("|---|---|---|")
    whole = sum(by_pass.values()) / n
    top = sorted(by_pass.items(), key=lambda kv: -kv[1])
    for name, t in top[:6]:
        print(f"| `{name}` | {t / n:.2f} | {100 * t / n / whole:.0f} % |")
    rest = sum(t for _, t in top[6:]) / n
    print(f"| {len(top) - 6} other passes | {rest:.2f} | {100 * rest / whole:.0f} % |")
    t_llvm = sum(llvm) / n
    print(
        f"\nof which LLVM (optimisation and machine code, inside the lowering): {t_llvm:.2f} s "
        f"({100 * t_llvm / whole:.0f} %); numba's own Python: {whole - t_llvm:.2f} s"
    )


if __name__ == "__main__":
    main()
