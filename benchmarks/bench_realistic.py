"""Cost of the realistic drive beside the average-value model, measured side by side.

Run from the repository root with the imdrive venv::

    python benchmarks/bench_realistic.py [--rounds N] [--batch N] [--json PATH]

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
``--batch N``, the kernel time per drive of N realistic drives in ``simulate_batch`` (both
cores) beside the single runs, and the estimate of an 800-run envelope of 14.5 s drives.
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
    from imdrive.config.scenario import Scenario
    from imdrive.run.batch import simulate_batch
    from imdrive.run.simulate import simulate

    scs = [
        Scenario.read("sensorless-realistic", [f"simulation.t_end_s={t_end}", f"sensor.seed={s}"])
        for s in range(n)
    ]
    simulate_batch(scs[:2])  # compile or load
    t0 = time.perf_counter()
    simulate_batch(scs)
    wall = time.perf_counter() - t0
    single = []
    for sc in scs[:3]:
        single.append(simulate(sc).wall_time_s)
    return {"n": n, "t_end_s": t_end, "batch_wall_s": wall, "single_wall_s": single}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Realistic drive vs the average model.")
    ap.add_argument("--rounds", type=int, default=9, help="rounds of the four variants")
    ap.add_argument("--batch", type=int, default=0, help="also N realistic drives in a batch")
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
        per = b["batch_wall_s"] / b["n"]
        print(
            f"  batch of {b['n']} realistic 1 s drives: {b['batch_wall_s']:.2f} s wall, "
            f"{1e3 * per:.1f} ms per drive; single runs {span(b['single_wall_s'], 'ms', 1e3)} "
            f"(kernel); per drive on {os.cpu_count()} cores vs one: "
            f"{statistics.median(b['single_wall_s']) / per:.2f}x throughput"
        )
        result["batch"] = b
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
