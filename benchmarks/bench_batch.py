"""Speed and memory of the batch engine, and imdrive beside gym-electric-motor and motulator.

Run from the repository root with the imdrive venv::

    python benchmarks/bench_batch.py [--repeat N] [--sizes 1,10,100,1000,10000] [--json PATH]
                                     [--peers] [--quick]

Measures

1. **Single drive, per preset.** Every preset of ``imdrive presets``: median over ``--repeat``
   runs of the kernel time of ``simulate()`` (``SimulationResult.wall_time_s``) and the
   real-time factor (simulated seconds per wall second), one core.
2. **Batch scaling and throughput.** N one-second sensorless drives (``sensorless`` preset,
   ramp to the speed 0.1 ... 0.4 s, load step at 0.5 s, t_end = 1 s, Ts = 100 us), each with its
   own R2_hat/R2 in [0.6, 1.4], final speed in [100, 1500] rpm and load in [0, 12] N m (a random
   sweep, seed 0), for N in ``--sizes``: wall time of the whole ``simulate_batch()`` call
   (scenarios built from a generator, arrays, kernel, metrics table) and of the kernel alone,
   and the throughput in drive-control-periods per second, on all cores (numba's threads;
   since 2026-12-01 the next block's set-up runs beside the kernels, so the kernel's wall
   time includes sharing the cores with it, and ``total - kernel`` is what does not overlap); the
   same on one thread for N = 100, for the parallel speed-up.
3. **Memory per drive** (no logs), in a fresh subprocess per N (N = 2 000, 20 000, 100 000 very
   short drives, t_end = 10 ms, since memory without logs does not depend on the drive length):
   the growth of the peak RSS (``ru_maxrss``) and the tracemalloc peak of one
   ``simulate_batch()`` call, after a warm-up batch that loads the kernel and allocates the
   per-thread scratch, divided by N.
4. **Peers** (``--peers``): the free acceleration of bench_motulator.py / bench_gem.py in the peers
   venv (``benchmarks/.venv-peers``, see README.md), beside imdrive's ``simulate()`` of the same
   run and imdrive's cost per drive in a batch of 100 such runs; wall-time ratios.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np
from _measured import factor_span, machine_line, span

HERE = Path(__file__).resolve().parent
PEERS_PYTHON = HERE / ".venv-peers" / "bin" / "python"

DRIVES = """
name = "bench-1s-sensorless"
base = "sensorless"
samples = {n}
seed = 0

[set]
simulation.t_end_s = {t_end}
control.speed_ref_rpm = {{ initial = 0, changes = [{{ at = 0.1, to = 1000, over = 0.3 }}] }}
load.torque_Nm = {{ initial = 0, changes = [{{ at = 0.5, to = 12 }}] }}

[axes]
R2_ratio = {{ min = 0.6, max = 1.4 }}
speed_rpm = {{ min = 100, max = 1500 }}
load_Nm = {{ min = 0, max = 12 }}
"""


def drives(n: int, t_end: float = 1.0):
    """The benchmark's sweep of ``n`` drives (validated, not yet built)."""
    from imdrive.sweep import parse_sweep

    return parse_sweep(DRIVES.format(n=n, t_end=t_end))


def bench_presets(repeat: int) -> dict:
    from imdrive.config.presets import preset_names
    from imdrive.config.scenario import Scenario
    from imdrive.run.simulate import simulate

    out = {}
    for name in preset_names():
        sc = Scenario.read(name)
        simulate(sc)  # compile or load; not timed
        walls = [simulate(sc).wall_time_s for _ in range(repeat)]
        w = statistics.median(walls)
        out[name] = {
            "kernel_walls_s": walls,
            "simulated_s": sc.simulation.t_end_s,
            "control_periods": sc.simulation.n_steps,
            "kernel_wall_s": w,
            "real_time_factor": sc.simulation.t_end_s / w,
            "us_per_period": 1e6 * w / sc.simulation.n_steps,
        }
    return out


def bench_scaling(sizes: list[int], repeat: int = 1) -> dict:
    import numba

    from imdrive.run.batch import simulate_batch

    sw = drives(4)
    simulate_batch(sw.scenario(i) for i in range(4))  # compile or load
    simulate_batch((sw.scenario(i) for i in range(4)), parallel=False)
    rows = {}
    threads = numba.get_num_threads()
    for n in sizes:
        sw = drives(n)
        totals = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            res = simulate_batch(sw.scenario(i) for i in range(n))
            totals.append(time.perf_counter() - t0)
        total = statistics.median(totals)
        m = res.metrics
        rows[n] = {
            "total_walls_s": totals,
            "threads": threads,
            "total_wall_s": total,
            "kernel_wall_s": res.wall_time_s,
            "control_periods": res.control_periods,
            "periods_per_s_total": res.control_periods / total,
            "periods_per_s_kernel": res.periods_per_s,
            "diverged": int(m["diverged"].sum()),
            "mean_abs_speed_error_rpm": float(np.nanmean(np.abs(m["speed_error_rpm"]))),
        }
    sw = drives(100)
    t0 = time.perf_counter()
    res = simulate_batch((sw.scenario(i) for i in range(100)), parallel=False)
    total = time.perf_counter() - t0
    one = {
        "threads": 1,
        "total_wall_s": total,
        "kernel_wall_s": res.wall_time_s,
        "control_periods": res.control_periods,
        "periods_per_s_total": res.control_periods / total,
        "periods_per_s_kernel": res.periods_per_s,
    }
    return {"parallel": rows, "one_thread_N100": one}


_MEMORY_CHILD = textwrap.dedent(
    """
    import json, resource, sys, tracemalloc
    sys.path.insert(0, {here!r})
    from bench_batch import drives
    from imdrive.run.batch import simulate_batch
    n = {n}
    warm = drives(8, {t_end})
    simulate_batch(warm.scenario(i) for i in range(8))
    sw = drives(n, {t_end})
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    tracemalloc.start()
    res = simulate_batch(sw.scenario(i) for i in range(n))
    cur, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    kept = int(res.metrics.memory_usage(deep=True).sum())
    print(json.dumps(dict(n=n, rss_kB=rss1 - rss0, tracemalloc_peak=peak,
                          tracemalloc_kept=cur, table_bytes=kept)))
    """
)


def bench_memory(sizes, t_end: float = 0.01) -> dict:
    out = {}
    for n in sizes:
        code = _MEMORY_CHILD.format(here=str(HERE), n=n, t_end=t_end)
        proc = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True
        )
        r = json.loads(proc.stdout.strip().splitlines()[-1])
        out[n] = {
            "rss_growth_bytes_per_drive": 1024 * r["rss_kB"] / n,
            "tracemalloc_peak_bytes_per_drive": r["tracemalloc_peak"] / n,
            "result_table_bytes_per_drive": r["table_bytes"] / n,
        }
    ns = sorted(out)
    # slope between the smallest and the largest N: the cost of one more drive
    a, b = ns[0], ns[-1]
    for key in ("rss_growth_bytes_per_drive", "tracemalloc_peak_bytes_per_drive"):
        slope = (out[b][key] * b - out[a][key] * a) / (b - a)
        out[f"slope_{key}"] = slope
    return out


def bench_peers(repeat: int) -> dict:
    from imdrive.config.scenario import Scenario
    from imdrive.run.batch import simulate_batch
    from imdrive.run.simulate import simulate

    if not PEERS_PYTHON.exists():
        print(f"(no peers venv at {PEERS_PYTHON}: peers skipped, see README.md)")
        return {}
    sc = Scenario.read("free-acceleration")
    simulate(sc)
    walls = []
    for _ in range(7):
        t0 = time.perf_counter()
        r = simulate(sc)
        walls.append(time.perf_counter() - t0)
    simulate_batch([sc] * 4)
    t0 = time.perf_counter()
    b = simulate_batch([sc] * 100)
    batch_per_drive = (time.perf_counter() - t0) / 100
    out = {
        "imdrive_simulate_wall_s": statistics.median(walls),
        "imdrive_kernel_wall_s": r.wall_time_s,
        "imdrive_batch100_wall_per_drive_s": batch_per_drive,
        "imdrive_batch100_kernel_per_drive_s": b.wall_time_s / 100,
    }
    with tempfile.TemporaryDirectory() as tmp:
        r.save(tmp, figures=False, csv=True)
        csv = str(Path(tmp) / "timeseries.csv")
        for peer, script in (("gem", "bench_gem.py"), ("motulator", "bench_motulator.py")):
            js = Path(tmp) / f"{peer}.json"
            cmd = [str(PEERS_PYTHON), str(HERE / script), "--repeat", str(repeat)]
            cmd += ["--json", str(js), "--imdrive-csv", csv]
            if peer == "motulator":
                cmd.append("--tight")
            proc = subprocess.run(cmd, capture_output=True, text=True)
            if proc.returncode != 0:
                print(f"({script} failed: {proc.stderr.strip().splitlines()[-1:]})")
                continue
            out[peer] = json.loads(js.read_text())
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3, help="timed runs per preset / peer run")
    ap.add_argument("--sizes", default="1,10,100,1000,10000", help="batch sizes N")
    ap.add_argument(
        "--repeat-batch", type=int, default=1, help="timed batches per size N (range printed)"
    )
    ap.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    ap.add_argument("--peers", action="store_true", help="also run gym-electric-motor, motulator")
    ap.add_argument("--quick", action="store_true", help="sizes 1,10,100; small memory runs")
    ap.add_argument("--skip", default="", help="comma-separated: presets,scaling,memory")
    args = ap.parse_args(argv)
    sizes = [1, 10, 100] if args.quick else [int(s) for s in args.sizes.split(",")]
    skip = set(filter(None, args.skip.split(",")))

    import numba

    import imdrive

    info = {
        "imdrive": imdrive.__version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "numba": numba.__version__,
        "numba_threads": numba.get_num_threads(),
        "threading_layer": None,
        "cpus": os.cpu_count(),
        "date": time.strftime("%Y-%m-%d"),
    }
    results: dict = {"info": info}
    print(
        f"imdrive {info['imdrive']}, numpy {info['numpy']}, numba {info['numba']}, "
        f"{info['numba_threads']} numba threads"
    )
    print(machine_line())
    if "presets" not in skip:
        pr = results["presets"] = bench_presets(args.repeat)
        print(f"\nsingle drive per preset (kernel wall time, one core, {args.repeat} runs each)")
        for name, r in pr.items():
            w = r["kernel_walls_s"]
            rtf = factor_span(r["simulated_s"], w)
            print(
                f"  {name:<24}{r['simulated_s']:>5g} s {span(w, 'ms', 1e3, 1):>34}"
                f"{rtf:>11} real time"
            )
    if "scaling" not in skip:
        sc = results["scaling"] = bench_scaling(sizes, args.repeat_batch)
        try:
            info["threading_layer"] = numba.threading_layer()
        except ValueError:
            pass
        print("\nbatch of N one-second sensorless drives (all numba threads)")
        print(
            f"  {'N':>7}{'total':>10}{'kernel':>10}{'Mperiods/s':>12}{'(kernel)':>10}"
            f"{'diverged':>10}"
        )
        for n, r in sc["parallel"].items():
            print(
                f"  {n:>7}{r['total_wall_s']:>9.2f}s{r['kernel_wall_s']:>9.2f}s"
                f"{r['periods_per_s_total'] / 1e6:>12.2f}{r['periods_per_s_kernel'] / 1e6:>10.2f}"
                f"{r['diverged']:>10}"
            )
            if len(r["total_walls_s"]) > 1:
                print(f"  {'':>7}total over the runs: {span(r['total_walls_s'])}")
        o = sc["one_thread_N100"]
        print(
            f"  N = 100 on one thread: {o['total_wall_s']:.2f} s, "
            f"{o['periods_per_s_kernel'] / 1e6:.2f} M periods/s (kernel)"
        )
    if "memory" not in skip:
        mem_sizes = (500, 2_000, 8_000) if args.quick else (2_000, 20_000, 100_000)
        mem = results["memory"] = bench_memory(mem_sizes)
        print("\nmemory per drive without logs (fresh process per N, 10 ms drives)")
        for n, r in mem.items():
            if isinstance(n, int):
                print(
                    f"  N = {n:>6}: peak RSS growth {r['rss_growth_bytes_per_drive']:7.0f} B, "
                    f"tracemalloc peak {r['tracemalloc_peak_bytes_per_drive']:6.0f} B, "
                    f"metrics table {r['result_table_bytes_per_drive']:5.0f} B per drive"
                )
        print(
            f"  slope (largest vs smallest N): RSS "
            f"{mem['slope_rss_growth_bytes_per_drive']:.0f} B, tracemalloc "
            f"{mem['slope_tracemalloc_peak_bytes_per_drive']:.0f} B per additional drive"
        )
    if args.peers:
        pe = results["peers"] = bench_peers(args.repeat)
        if pe:
            base = pe["imdrive_simulate_wall_s"]
            per = pe["imdrive_batch100_wall_per_drive_s"]
            print("\nfree acceleration, 1.5 s (15 000 periods): wall time and ratio to imdrive")
            print(f"  {'imdrive simulate()':<36}{base * 1e3:9.2f} ms")
            print(f"  {'imdrive per drive in a batch of 100':<36}{per * 1e3:9.2f} ms")
            for peer in ("gem", "motulator"):
                if peer not in pe:
                    continue
                for label, r in pe[peer]["runs"].items():
                    name = f"{peer} {label.split(' (')[0]}"
                    print(
                        f"  {name:<36}{r['wall_s']:9.2f} s   "
                        f"x{r['wall_s'] / base:8.0f} simulate(), x{r['wall_s'] / per:8.0f} batch;"
                        f"  max |di| {r.get('max_current_diff_A', float('nan')):.1e} A"
                    )
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=2, default=str) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
