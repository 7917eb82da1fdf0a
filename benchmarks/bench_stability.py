"""Time of a 50 x 40 stability map (imdrive.stability.stability_map) once compiled.

Usage: ``python benchmarks/bench_stability.py [--repeat N] [--preset NAME]``. The first call
loads or compiles the kernels (reported apart); then ``--repeat`` timed maps over speeds
0 ... 1500 rpm x load torques -24 ... 24 N m, median and best printed.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _measured import machine_line, span

from imdrive.config.scenario import Scenario
from imdrive.stability.maps import stability_map


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--preset", default="sensorless")
    args = ap.parse_args()
    print(machine_line())
    sc = Scenario.read(args.preset)
    speeds = np.linspace(0.0, 1500.0, 50)
    torques = np.linspace(-24.0, 24.0, 40)
    t0 = time.perf_counter()
    stability_map(sc, speeds[:2], torques[:2])
    print(f"first call (load or compile kernels): {time.perf_counter() - t0:.2f} s")
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        df = stability_map(sc, speeds, torques)
        times.append(time.perf_counter() - t0)
    n_ok = int((df.status == "ok").sum())
    print(
        f"50 x 40 map ({len(df)} points, {n_ok} with a steady state, {int(df.stable.sum())} "
        f"stable): {span(times, digits=3)}"
    )


if __name__ == "__main__":
    main()
