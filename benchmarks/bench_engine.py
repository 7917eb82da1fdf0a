"""Speed of the imdrive engine on the free-acceleration preset.

Run from the repository root with the imdrive venv::

    python benchmarks/bench_engine.py [--repeat N] [--json PATH] [--motulator]

Measures

1. the free-acceleration preset (1.5 s at Ts = 100 us, 15 000 control periods) once compiled:
   median over ``--repeat`` runs of the kernel time alone (``SimulationResult.wall_time_s``) and
   of the whole ``simulate()`` call (arrays, log allocation, kernel, result object), as wall time
   and real-time factor (simulated seconds per wall second);
2. cold start: ``imdrive run free-acceleration`` in a subprocess with an empty numba cache
   (``NUMBA_CACHE_DIR`` set to a fresh temporary folder), wall time of the whole command
   (interpreter start, imports, compilation, run, CSV, figures, summary);
3. warm start: the same command again with the same cache folder.

With ``--motulator`` it also runs ``benchmarks/bench_motulator.py`` in the peers venv
(``benchmarks/.venv-peers``, see README.md) and prints the wall-time ratio.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _measured import factor_span, machine_line, span

HERE = Path(__file__).resolve().parent
PEERS_PYTHON = HERE / ".venv-peers" / "bin" / "python"


def _cpu_kernel_times(sc, repeat: int) -> list[float]:
    """Process CPU times of the kernel alone, s (robust on a shared, loaded machine)."""
    from imdrive.kernels.engine import run_drive
    from imdrive.run.build import build_arrays, copy_state
    from imdrive.run.simulate import new_log

    a = build_arrays(sc)
    log = new_log(a.n_steps // a.log_every + 1)
    run_drive(a.params, copy_state(a.state0), 0, 1, log, a.log_every)  # compiled or loaded
    times = []
    for _ in range(repeat):
        S = copy_state(a.state0)
        t0 = time.process_time()
        run_drive(a.params, S, 0, a.n_steps, log, a.log_every)
        times.append(time.process_time() - t0)
    return times


def bench_kernel(repeat: int, preset: str = "free-acceleration", cpu: bool = False) -> dict:
    from imdrive.config.scenario import Scenario
    from imdrive.run.simulate import simulate

    name, _, sets = preset.partition(":")
    sc = Scenario.read(name, [o for o in sets.split(",") if o])
    t_sim = sc.simulation.t_end_s
    res = simulate(sc)  # compile or load from the cache; not timed
    kernel, whole = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        res = simulate(sc)
        whole.append(time.perf_counter() - t0)
        kernel.append(res.wall_time_s)
    if cpu:
        kernel = _cpu_kernel_times(sc, repeat)
    k, w = statistics.median(kernel), statistics.median(whole)
    s = res.signals
    rpm = s["speed_rpm"]
    t1700 = math.nan
    if rpm.max() >= 1700.0:  # free acceleration: the time to 1700 rpm is a sanity figure
        i = int(np.argmax(rpm >= 1700.0))
        t1700 = float(np.interp(1700.0, rpm[i - 1 : i + 1], s["time_s"][i - 1 : i + 1]))
    return {
        "preset": preset,
        "simulated_s": t_sim,
        "control_periods": sc.simulation.n_steps,
        "kernel_wall_s": k,
        "kernel_real_time_factor": t_sim / k,
        "kernel_us_per_period": 1e6 * k / sc.simulation.n_steps,
        "simulate_wall_s": w,
        "simulate_real_time_factor": t_sim / w,
        "kernel_clock": "process CPU time" if cpu else "wall time",
        "kernel_walls_s": kernel,
        "simulate_walls_s": whole,
        "peak_torque_Nm": float(s["torque_Nm"].max()),
        "peak_current_A": float(np.hypot(s["i_alpha_A"], s["i_beta_A"]).max()),
        "time_to_1700_rpm_s": t1700,
        "final_speed_rpm": float(rpm[-1]),
    }


def _run_cli(cache_dir: str, out_dir: str) -> tuple[float, dict]:
    env = dict(os.environ, NUMBA_CACHE_DIR=cache_dir)
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "imdrive", "run", "free-acceleration", "--out", out_dir, "-q"],
        env=env,
        capture_output=True,
        text=True,
    )
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"imdrive run failed ({proc.returncode}):\n{proc.stderr}")
    summary = json.loads((Path(out_dir) / "summary.json").read_text())
    return wall, summary


def bench_cli() -> dict:
    with tempfile.TemporaryDirectory(prefix="imdrive-bench-") as tmp:
        cache = Path(tmp) / "numba-cache"
        cache.mkdir()
        cold, s_cold = _run_cli(str(cache), str(Path(tmp) / "out-cold"))
        n_cached = sum(1 for _ in cache.rglob("*.nbi"))
        warm, s_warm = _run_cli(str(cache), str(Path(tmp) / "out-warm"))
    return {
        "cold_wall_s": cold,
        "cold_kernel_startup_s": s_cold["kernel_startup_s"],
        "warm_wall_s": warm,
        "warm_kernel_startup_s": s_warm["kernel_startup_s"],
        "warm_kernel_wall_s": s_warm["wall_time_s"],
        "cached_functions": n_cached,
    }


def bench_motulator(imdrive_csv: str | None) -> dict | None:
    if not PEERS_PYTHON.exists():
        print(f"(no peers venv at {PEERS_PYTHON}: motulator skipped, see README.md)")
        return None
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "motulator.json"
        cmd = [str(PEERS_PYTHON), str(HERE / "bench_motulator.py"), "--json", str(out)]
        if imdrive_csv:
            cmd += ["--imdrive-csv", imdrive_csv]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        return json.loads(out.read_text())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Benchmark the imdrive engine (free acceleration).")
    ap.add_argument("--repeat", type=int, default=7, help="timed runs of simulate() (median)")
    ap.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    ap.add_argument(
        "--preset",
        action="append",
        help="preset(s) whose kernel time to measure, each optionally with overrides as "
        "NAME:key=value,key=value (repeatable; default free-acceleration)",
    )
    ap.add_argument(
        "--cpu",
        action="store_true",
        help="time the kernel in process CPU time (median), not wall time: steadier when "
        "other jobs share the cores",
    )
    ap.add_argument("--no-cli", action="store_true", help="skip the cold/warm CLI runs")
    ap.add_argument("--motulator", action="store_true", help="also run bench_motulator.py")
    args = ap.parse_args(argv)

    import numba

    import imdrive

    info = {
        "imdrive": imdrive.__version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "numba": numba.__version__,
        "cpus": os.cpu_count(),
        "machine": platform.machine(),
        "date": time.strftime("%Y-%m-%d"),
    }
    presets = args.preset or ["free-acceleration"]
    results: dict = {"info": info, "kernel": bench_kernel(args.repeat, presets[0], args.cpu)}
    results["other_presets"] = [bench_kernel(args.repeat, p, args.cpu) for p in presets[1:]]
    if not args.no_cli:
        results["cli"] = bench_cli()
    if args.motulator:
        with tempfile.TemporaryDirectory() as tmp:
            subprocess.run(
                [sys.executable, "-m", "imdrive", "run", "free-acceleration", "--out", tmp, "-q"]
                + ["--set", "output.figures=false"],
                check=True,
            )
            results["motulator"] = bench_motulator(str(Path(tmp) / "timeseries.csv"))

    k = results["kernel"]
    clock = "CPU" if args.cpu else "wall"

    def kernel_rows(r: dict, label: str) -> list[tuple[str, str, str]]:
        us = [1e6 * t / r["control_periods"] for t in r["kernel_walls_s"]]
        return [
            (
                f"{label} kernel only, {clock} time",
                span(r["kernel_walls_s"], "ms", 1e3),
                f"{factor_span(r['simulated_s'], r['kernel_walls_s'])} real time",
            ),
            ("  per control period", span(us, "us", digits=3), ""),
        ]

    rows = [(f"{k['preset']}, {k['simulated_s']:g} s", f"{k['control_periods']} periods", "")]
    rows += kernel_rows(k, k["preset"])
    rows.append(
        (
            "whole simulate(), wall time",
            span(k["simulate_walls_s"], "ms", 1e3),
            f"{factor_span(k['simulated_s'], k['simulate_walls_s'])} real time",
        )
    )
    for o in results["other_presets"]:
        rows += kernel_rows(o, f"{o['preset']} ({o['simulated_s']:g} s)")
    if "cli" in results:
        c = results["cli"]
        rows += [
            (
                "imdrive run, cold numba cache",
                f"{c['cold_wall_s']:.2f} s",
                f"compile {c['cold_kernel_startup_s']:.2f} s",
            ),
            (
                "imdrive run, warm numba cache",
                f"{c['warm_wall_s']:.2f} s",
                f"load {c['warm_kernel_startup_s']:.3f} s",
            ),
        ]
    m = results.get("motulator")
    if m:
        (label, r), *_ = m["runs"].items()
        ratio = k["simulate_wall_s"] / r["wall_s"]
        results["imdrive_over_motulator"] = ratio
        rows += [
            (
                f"motulator {m['motulator']} {label.split(' (')[0]}",
                f"{r['wall_s']:.2f} s",
                f"{r['real_time_factor']:.2f}x",
            ),
            (
                "imdrive simulate() / motulator wall time",
                f"{ratio:.2e}",
                f"imdrive {1 / ratio:.0f}x faster",
            ),
        ]
    w = max(len(r[0]) for r in rows)
    wb = max(len(r[1]) for r in rows)
    print(f"imdrive {info['imdrive']}, numpy {info['numpy']}, numba {info['numba']}")
    print(machine_line())
    for a, b, c in rows:
        print(f"  {a:<{w}}  {b:>{wb}}  {c}")
    sanity = [
        ("peak torque, N m", "peak_torque_Nm"),
        ("peak |i_s|, A", "peak_current_A"),
        ("time to 1700 rpm, s", "time_to_1700_rpm_s"),
        ("final speed, rpm", "final_speed_rpm"),
    ]
    print("  sanity:" + ("  (imdrive | motulator)" if m else ""))
    for name, key in sanity:
        other = f"  | {r[key]:.6g}" if m else ""
        print(f"    {name:<22} {k[key]:.6g}{other}")
    if m and "max_current_diff_A" in r:
        print(f"    max |i_s| difference at the samples: {r['max_current_diff_A']:.2e} A")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
