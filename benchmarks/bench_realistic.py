"""Cost of the realistic drive beside the average-value model, measured side by side.

Run from the repository root with the imdrive venv::

    python benchmarks/bench_realistic.py [--rounds N] [--batch N] [--envelope N] [--memory]
        [--json PATH]

Four variants of the 3 s ``sensorless`` scenario, timed in turn within each round (so a
load change on the shared machine hits them alike) in process CPU time of the kernel alone
(``run_drive``, one core, numba cache warm):

1. ``average``: the ``sensorless`` preset (average-value inverter);
2. ``switching + dead time``: the same on the switching bridge, 2 us dead time, feed-forward
   compensation (no saturation);
3. ``realistic, no saturation``: ``sensorless-realistic`` with ``plant.saturation.enabled =
   false`` (bridge, dead time, 1 V drops, delay, sensors with noise and ADC);
4. ``realistic``: ``sensorless-realistic`` (everything, main-flux saturation on).

Each round's cost ratio is the variant's time over the ``average`` time of the same round;
the script prints the range (lowest-highest, median, number of rounds) of the times and of the
ratios. It also prints the record sizes of ``DriveParams``/``DriveState`` per drive and, with
``--batch N``, the process CPU time per drive of N realistic 1 s drives in ``simulate_batch``
(both cores) beside a single run's kernel time; with ``--envelope N``, N realistic 14.5 s
drives of an envelope (load 0-12 N m) in one batch (``--envelope 800``: the whole envelope,
measured; fewer: extrapolated to 800 runs); with
``--memory``, what a realistic drive costs in memory in a batch (tracemalloc).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

from _measured import machine_line, span

VARIANTS = {
    "average": ("sensorless", []),
    "switching + dead time": (
        "sensorless",
        [
            "inverter.model=switching",
            "inverter.dead_time_s=2e-6",
            "control.dead_time_compensation=feedforward",
        ],
    ),
    "realistic, no saturation": ("sensorless-realistic", ["plant.saturation.enabled=false"]),
    "realistic": ("sensorless-realistic", []),
}


def _prepare(name: str, overrides: list[str]):
    from imdrive.config.scenario import Scenario
    from imdrive.kernels.engine import run_drive
    from imdrive.run.build import build_arrays, copy_state
    from imdrive.run.simulate import new_log

    sc = Scenario.read(name, overrides)
    a = build_arrays(sc)
    log = new_log(a.n_steps // a.log_every + 1)
    run_drive(a.params, copy_state(a.state0), 0, 1, log, a.log_every)  # compile or load

    def once() -> float:
        S = copy_state(a.state0)
        t0 = time.process_time()
        run_drive(a.params, S, 0, a.n_steps, log, a.log_every)
        return time.process_time() - t0

    return sc, a, once


def record_sizes(a) -> dict:
    """Bytes per drive of every record of ``DriveParams`` and ``DriveState``."""
    out = {}
    for label, tup in (("params", a.params), ("state", a.state0)):
        for field, arr in tup._asdict().items():
            if field == "tables":  # shared by all drives (indexed by table_idx)
                continue
            out[f"{label}.{field}"] = int(arr.nbytes // max(arr.shape[0], 1))
    return out


def bench_batch(n: int, t_end: float) -> dict:
    """``n`` realistic drives of ``t_end`` s in one ``simulate_batch`` call (both cores) beside
    3 single runs: wall and process CPU time (all threads) of the batch, kernel CPU time of the
    single runs. On a shared machine the batch's wall time depends on the other jobs; its CPU
    time per drive against a single run's is the per-drive cost."""
    from imdrive.config.scenario import Scenario
    from imdrive.kernels.engine import run_drive
    from imdrive.run.batch import simulate_batch
    from imdrive.run.build import build_arrays, copy_state
    from imdrive.run.simulate import new_log

    scs = [
        Scenario.read("sensorless-realistic", [f"simulation.t_end_s={t_end}", f"sensor.seed={s}"])
        for s in range(n)
    ]
    simulate_batch(scs[:2])  # compile or load
    c0, w0 = time.process_time(), time.perf_counter()
    res = simulate_batch(scs)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    single = []
    for sc in scs[:3]:
        a = build_arrays(sc)
        log = new_log(a.n_steps // a.log_every + 1, a.log)
        S = copy_state(a.state0)
        t0 = time.process_time()
        run_drive(a.params, S, 0, a.n_steps, log, a.log_every)
        single.append(time.process_time() - t0)
    return {"n": n, "t_end_s": t_end, "batch_wall_s": wall, "batch_cpu_s": cpu,
            "batch_kernel_wall_s": res.wall_time_s, "single_cpu_s": single}  # fmt: skip


#: The kernel's stop codes (``imdrive.kernels.stages.S_*``) and the batch's failed build.
_STATUS = {0: "ran to the end", 1: "NaN", 2: "current limit", 3: "speed limit", -1: "failed"}


def bench_envelope(n: int) -> dict:
    """An envelope of ``n`` realistic drives of 14.5 s (load torque 0-12 N m in ``n`` steps,
    one sensor seed each) in one ``simulate_batch`` call (``n = 800``: the whole envelope;
    fewer: a subset, 800 runs extrapolated from its process CPU time, both cores, and wall
    time). ``read_s`` is the wall time of reading the ``n`` scenarios before the batch."""
    from imdrive.config.scenario import Scenario
    from imdrive.run.batch import simulate_batch

    r0 = time.perf_counter()
    scs = [
        Scenario.read("sensorless-realistic", ["simulation.t_end_s=14.5",
                      f"load.torque_Nm={12.0 * j / max(n - 1, 1):.4f}", f"sensor.seed={j}"])
        for j in range(n)
    ]  # fmt: skip
    read = time.perf_counter() - r0
    simulate_batch(scs[:1])  # compile or load
    c0, w0 = time.process_time(), time.perf_counter()
    res = simulate_batch(scs)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    periods = int(res.control_periods)
    return {"n": n, "cpu_s": cpu, "wall_s": wall, "read_s": read, "control_periods": periods,
            "statuses": {_STATUS.get(int(k), str(k)): int(v)
                         for k, v in res.metrics["status"].value_counts().items()},
            "kernel_wall_s": res.wall_time_s,
            "cpu_800_s": 800 * cpu / n, "wall_800_s": 800 * wall / n}  # fmt: skip


def bench_memory(sizes=(200, 1200)) -> dict:
    """tracemalloc of ``simulate_batch`` over realistic 10 ms drives: peak during the call and
    what stays after it, per drive and as the slope between the two sizes."""
    import tracemalloc

    from imdrive.config.scenario import Scenario
    from imdrive.run.batch import simulate_batch

    def scs(n):
        return (
            Scenario.read("sensorless-realistic", ["simulation.t_end_s=0.01", f"sensor.seed={i}"])
            for i in range(n)
        )

    simulate_batch(scs(4))
    out = {}
    for n in sizes:
        tracemalloc.start()
        res = simulate_batch(scs(n))
        cur, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        out[n] = {"peak_bytes": peak, "kept_bytes": cur}
        del res
    a, b = sizes
    out["kept_slope_bytes_per_drive"] = (out[b]["kept_bytes"] - out[a]["kept_bytes"]) / (b - a)
    out["peak_slope_bytes_per_drive"] = (out[b]["peak_bytes"] - out[a]["peak_bytes"]) / (b - a)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Realistic drive vs the average model.")
    ap.add_argument("--rounds", type=int, default=9, help="rounds of the four variants")
    ap.add_argument("--batch", type=int, default=0, help="also N realistic drives in a batch")
    ap.add_argument("--envelope", type=int, default=0, help="N 14.5 s drives of an envelope")
    ap.add_argument("--memory", action="store_true", help="memory per drive in a batch")
    ap.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    args = ap.parse_args(argv)

    prepared = {k: _prepare(*v) for k, v in VARIANTS.items()}
    times: dict[str, list[float]] = {k: [] for k in VARIANTS}
    for _ in range(args.rounds):
        for k, (_, _, once) in prepared.items():
            times[k].append(once())
    n_steps = prepared["average"][1].n_steps
    t_sim = prepared["average"][0].simulation.t_end_s
    ratios = {
        k: [t / ta for t, ta in zip(times[k], times["average"], strict=True)] for k in VARIANTS
    }
    print(machine_line())
    print(f"3 s drives, {n_steps} periods, kernel in process CPU time, {args.rounds} rounds")
    for k in VARIANTS:
        us = [1e6 * t / n_steps for t in times[k]]
        rt = [t_sim / t for t in times[k]]
        line = f"  {k:<26} {span(us, 'us/period', digits=3)}"
        line += f"; real time {min(rt):.0f}-{max(rt):.0f}x"
        if k != "average":
            line += f"; cost vs average {span(ratios[k], 'x')}"
        print(line)
    sizes = record_sizes(prepared["realistic"][1])
    p_b = sum(v for f, v in sizes.items() if f.startswith("params."))
    s_b = sum(v for f, v in sizes.items() if f.startswith("state."))
    print(f"  records per drive: DriveParams {p_b} B, DriveState {s_b} B (tables shared)")
    big = sorted(sizes.items(), key=lambda kv: -kv[1])[:4]
    print("    largest: " + ", ".join(f"{f} {v} B" for f, v in big))
    us_real = statistics.median(times["realistic"]) / n_steps
    env = 800 * 145_000 * us_real / (os.cpu_count() or 1)
    print(
        f"  estimate: 800 realistic drives of 14.5 s = {800 * 145_000:.3g} periods, "
        f"{env:.0f} s on {os.cpu_count()} cores at the median cost per period"
    )
    result = {"times_s": times, "ratios": ratios, "n_steps": n_steps, "record_bytes": sizes}
    if args.batch:
        b = bench_batch(args.batch, 1.0)
        cpu_per = b["batch_cpu_s"] / b["n"]
        s1 = statistics.median(b["single_cpu_s"])
        print(
            f"  batch of {b['n']} realistic 1 s drives: {b['batch_wall_s']:.2f} s wall, "
            f"{b['batch_cpu_s']:.2f} s CPU; CPU per drive {1e3 * cpu_per:.1f} ms against a "
            f"single run's kernel {span(b['single_cpu_s'], 'ms', 1e3)}: {cpu_per / s1:.2f}x"
        )
        result["batch"] = b
    if args.envelope:
        e = bench_envelope(args.envelope)
        what = "envelope" if e["n"] >= 800 else "envelope subset"
        line = (
            f"  {what}, {e['n']} drives of 14.5 s ({e['control_periods']:.3g} periods): "
            f"{e['cpu_s']:.1f} s CPU, {e['wall_s']:.1f} s wall in the batch "
            f"(kernels {e['kernel_wall_s']:.1f} s; + {e['read_s']:.1f} s reading the scenarios); "
            f"statuses {e['statuses']}"
        )
        if e["n"] < 800:
            line += (
                f"; 800 runs: {e['cpu_800_s']:.0f} s CPU "
                f"({e['cpu_800_s'] / (os.cpu_count() or 1):.0f} s on {os.cpu_count()} cores), "
                f"{e['wall_800_s']:.0f} s at this run's wall time"
            )
        print(line)
        result["envelope"] = e
    if args.memory:
        m = bench_memory()
        print(
            f"  memory per drive in a batch: kept {m['kept_slope_bytes_per_drive']:.0f} B, "
            f"peak {m['peak_slope_bytes_per_drive']:.0f} B (tracemalloc, slope N = 200 -> 1200)"
        )
        result["memory"] = m
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
