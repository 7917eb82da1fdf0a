"""Real-time factor of each speed estimator, one drive on one core, and the bench's wall time.

Run from the repository root with the imdrive venv::

    python benchmarks/bench_estimators.py [--repeat N] [--realistic] [--bench] [--csv PATH]

For every ``control.speed_feedback`` (and the R2-adapting variants) the ``sensorless`` preset
(3 s, Ts = 100 us: to 1000 rpm, rated load at 2 s) is run once to compile, then ``--repeat``
times; the median kernel time (``SimulationResult.wall_time_s``) gives the real-time factor
(simulated s per wall s). ``--realistic`` uses ``sensorless-realistic`` (switching inverter).
``--bench`` also times ``imdrive bench-estimators`` (the full protocol) in a subprocess.
``--csv PATH`` writes every timed run (estimator, kernel wall time, simulated time, machine):
docs/estimators.md's timing table is its rendering (``python -m imdrive.studies.doctables``).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--realistic", action="store_true")
    ap.add_argument("--bench", action="store_true")
    ap.add_argument("--csv", help="write every timed run to this CSV file")
    args = ap.parse_args()
    import numba

    numba.set_num_threads(1)
    from imdrive.bench.protocol import ESTIMATORS, machine_values  # the bench's configurations
    from imdrive.config.scenario import Scenario
    from imdrive.run.simulate import simulate

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from _measured import factor_span, machine_line, span

    preset = "sensorless-realistic" if args.realistic else "sensorless"
    machine = machine_line()
    print(machine)
    print(f"{preset}: {args.repeat} runs each, kernel wall time, one core")
    rows = []
    for name, ov in ESTIMATORS.items():
        values = machine_values(Scenario.read(preset).machine)  # the machine-relative placeholders
        for key, value in values.items():
            ov = [o.replace(key, value) for o in ov]
        sc = Scenario.read(preset, ov)
        simulate(sc)
        walls = [simulate(sc).wall_time_s for _ in range(args.repeat)]
        t_sim = sc.simulation.t_end_s
        rtf = factor_span(t_sim, walls)
        print(f"  {name:<14} {span(walls, 'ms', 1e3, 1):>34}  {rtf:>10} real time")
        rows += [(name, k, w, t_sim, preset) for k, w in enumerate(walls)]
    if args.csv:
        import csv

        with open(args.csv, "w", newline="") as f:
            out = csv.writer(f)
            out.writerow(["estimator", "run", "wall_s", "simulated_s", "preset", "machine"])
            out.writerows([*row, machine] for row in rows)
    if args.bench:
        with tempfile.TemporaryDirectory() as d:
            env = dict(os.environ, NUMBA_NUM_THREADS="2")
            cmd = [sys.executable, "-m", "imdrive", "bench-estimators", "--out", d, "-q"]
            subprocess.run(cmd, check=True, env=env)  # compile
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, env=env)
            wall = time.perf_counter() - t0
            print(f"  bench-estimators (full, 2 threads): {span([wall], digits=1)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
