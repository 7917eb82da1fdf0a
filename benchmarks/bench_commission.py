"""Wall time of one identification run (``imdrive commission``) on one core.

Run: ``python benchmarks/bench_commission.py [PRESET [KEY=VALUE ...]]`` (overrides as
``imdrive run --set``, e.g. ``'machine.preset="aalto-2.2kw"'``). The kernels are loaded (or
compiled) once before timing: the figure is the identification run with a warm kernel cache,
as for a drive commissioned after installation; the figures' PNGs are not included.
"""

from __future__ import annotations

import sys
import time

from _measured import machine_line, span


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    preset = argv[0] if argv else "sensorless-realistic"
    from imdrive.commission.identify import identify
    from imdrive.config.scenario import Scenario

    sc = Scenario.read(preset, argv[1:])
    identify(sc)  # loads (or compiles) the kernels
    times = []
    for _ in range(3):
        t0 = time.perf_counter()
        res = identify(sc)
        times.append(time.perf_counter() - t0)
    sim = sum(res.durations_s.values())
    print(machine_line())
    print(
        f"{preset} {' '.join(argv[1:])}: commissioning {min(times):.2f} s wall, best of 3 "
        f"({span(times)}; {sim:.1f} s simulated)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
