"""Where a preset's kernel spends its time: ``perf`` samples attributed to the compiled functions.

Run from the repository root with the imdrive venv (Linux, ``perf`` installed)::

    python benchmarks/profile_kernel.py [PRESET] [--set KEY=VALUE ...] [--seconds S] [--top N]

The kernels are compiled afresh into a temporary cache folder (code loaded from numba's cache
carries no function table), the address of every function of the compiled ``run_drive`` is
written to ``/tmp/perf-PID.map`` (the file ``perf`` reads for code generated at run time),
and ``perf record`` samples this process while it runs the preset's kernel over and over.
Prints each function's share of the samples (functions inlined into another count as it;
``libm`` calls such as ``sincos``, ``log``, ``exp`` appear by name), with numba's mangled
names shortened to the module and function. Shares, not times: read them beside
``bench_realistic.py``'s per-period times.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import threading
import time


def _short(name: str) -> str:
    """``imdrive.kernels.bridge.bridge_period`` from numba's mangled symbol (else as given)."""
    m = re.match(r"_ZN(?:7cpython)?((?:\d+[A-Za-z_]\w*?)+?)B\d", name)
    if not m:
        return name
    parts, rest = [], m.group(1)
    while rest:
        n = re.match(r"(\d+)", rest)
        length = int(n.group(1))
        start = len(n.group(1))
        parts.append(rest[start : start + length])
        rest = rest[start + length :]
    return ".".join(parts)


def _write_perf_map(run_drive) -> int:
    """Write ``/tmp/perf-PID.map`` for the functions of ``run_drive``'s compiled library."""
    lib = run_drive.overloads[run_drive.signatures[-1]].library
    ee = lib._codegen._engine._ee
    addrs = []
    for f in lib._final_module.functions:
        if f.is_declaration:
            continue
        ad = ee.get_function_address(f.name)
        if ad:
            addrs.append((ad, f.name))
    addrs.sort()
    with open(f"/tmp/perf-{os.getpid()}.map", "w") as fh:
        for i, (ad, name) in enumerate(addrs):
            end = addrs[i + 1][0] if i + 1 < len(addrs) else ad + 0x10000
            fh.write(f"{ad:x} {min(end - ad, 0x100000):x} {name}\n")
    return len(addrs)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("preset", nargs="?", default="sensorless-realistic")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--seconds", type=float, default=6.0, help="how long perf samples")
    ap.add_argument("--top", type=int, default=25, help="functions to print")
    args = ap.parse_args(argv)
    if shutil.which("perf") is None:
        print("profile_kernel.py needs Linux perf on the PATH", file=sys.stderr)
        return 2
    cache = tempfile.mkdtemp(prefix="imdrive-profile-")
    os.environ["IMDRIVE_CACHE_DIR"] = cache  # compile afresh: the function table exists
    from imdrive.config.scenario import Scenario
    from imdrive.kernels.engine import run_drive
    from imdrive.run.build import build_arrays, copy_state
    from imdrive.run.simulate import new_log

    a = build_arrays(Scenario.read(args.preset, args.set))
    log = new_log(a.n_steps // a.log_every + 1)
    run_drive(a.params, copy_state(a.state0), 0, 1, log, a.log_every)  # compile
    n_fn = _write_perf_map(run_drive)
    data = os.path.join(cache, "perf.data")
    done = threading.Event()
    runs = []

    def loop():
        while not done.is_set():
            S = copy_state(a.state0)
            t0 = time.process_time()
            run_drive(a.params, S, 0, a.n_steps, log, a.log_every)
            runs.append((time.process_time() - t0) / a.n_steps * 1e6)

    worker = threading.Thread(target=loop)
    worker.start()
    time.sleep(0.5)
    try:
        subprocess.run(
            ["perf", "record", "-q", "-p", str(os.getpid()), "-o", data, "--", "sleep",
             str(args.seconds)],
            check=True, stderr=subprocess.DEVNULL,
        )  # fmt: skip
    finally:
        done.set()
        worker.join()
    rep = subprocess.run(
        ["perf", "report", "-i", data, "--no-children", "--sort", "sym", "--stdio"],
        capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    med = sorted(runs)[len(runs) // 2]
    print(f"{args.preset} {' '.join(args.set)}: {len(runs)} runs, median {med:.3f} us per period")
    print(f"  ({n_fn} compiled functions; share of the samples:)")
    shown = 0
    for line in rep.splitlines():
        m = re.match(r"\s*([\d.]+)%\s+\[[.k]\]\s+(\S+)", line)
        if m and shown < args.top:
            print(f"  {float(m.group(1)):5.1f} %  {_short(m.group(2))}")
            shown += 1
    os.remove(f"/tmp/perf-{os.getpid()}.map")
    shutil.rmtree(cache, ignore_errors=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
