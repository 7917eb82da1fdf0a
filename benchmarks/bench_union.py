"""A batch of several estimators in one loop (their union's records) against each estimator's
own loop: the kernel's wall time for the same drives, and how many loops compile.

    python benchmarks/bench_union.py [--drives 40] [--repeat 5] [--t-end 1.0]

Runs ``--drives`` one-second ``sensorless`` drives per estimator (loads 0 to half the rated
torque), once as one batch of every estimator (one kernel, on
:mod:`imdrive.kernels.estimators.union`'s records) and once as one batch per estimator (each
its own kernel), after compiling both; prints the kernel wall times (``BatchResult.wall_time_s``,
both cores) and checks that every drive ends ``ok`` and that both give the same metrics.
What the first ``imdrive bench-estimators`` compiles is measured by ``bench_compile.py``.
"""

from __future__ import annotations

import argparse

import numpy as np
from _measured import machine_line, span

ESTIMATORS = ("mras", "afo", "ekf", "smo-mras", "reactive-mras")


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--drives", type=int, default=40, help="drives per estimator")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--t-end", type=float, default=1.0)
    args = ap.parse_args()
    from imdrive import simulate_batch
    from imdrive.config.scenario import Scenario

    def drives(est: str, n: int) -> list:
        return [
            Scenario.read(
                "sensorless",
                [
                    f'control.speed_feedback="{est}"',
                    f"simulation.t_end_s={args.t_end}",
                    f"load.torque_Nm={6.0 * k / n}",
                ],
            )
            for k in range(n)
        ]

    own = {e: drives(e, args.drives) for e in ESTIMATORS}
    mixed = [sc for e in ESTIMATORS for sc in own[e]]
    simulate_batch(mixed[:: args.drives])  # compile (or load) the union's loop
    for e in ESTIMATORS:
        simulate_batch(own[e][:1])  # and each estimator's
    print(machine_line())
    t_union, t_own = [], []
    for _ in range(args.repeat):
        one = simulate_batch(mixed)
        apart = [simulate_batch(own[e]) for e in ESTIMATORS]
        t_union.append(one.wall_time_s)
        t_own.append(sum(b.wall_time_s for b in apart))
        assert (one.metrics["status"] == 0).all()
        joined = np.concatenate([b.metrics["speed_error_rpm"].to_numpy() for b in apart])
        assert np.array_equal(one.metrics["speed_error_rpm"].to_numpy(), joined)
    n = len(mixed)
    print(f"{n} drives of {args.t_end} s, {len(ESTIMATORS)} estimators, kernel wall time:")
    print(f"  one batch, one loop (the union's): {span(t_union)}")
    print(f"  one batch per estimator, {len(ESTIMATORS)} loops: {span(t_own)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
