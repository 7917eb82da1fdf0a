"""What the R2 compensator costs: run time of the sensorless preset with and without it.

The target: the fuzzy-logic rotor-resistance compensator adds at most
10 % to the run time of the sensorless preset. Three variants of the same 3 s ``sensorless``
preset are timed (kernel time only, ``--repeat`` runs after a warm-up); the overhead is computed
from the fastest run of each variant (the least disturbed on a shared machine), and medians are
printed too:

* ``off``        : no compensator (the preset as shipped);
* ``paper``      : the paper's fuzzy compensator active for the whole run (10 ms period);
* ``injection``  : the persistent-excitation variant (prior art: Kubota & Matsuse, IEEE Trans.
                   Ind. Appl. 30(5), 1994) (injection + synchronous detection +
                   the same table), active for the whole run.

Usage::

    python benchmarks/bench_compensator.py [--repeat 15] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import statistics

from _measured import factor_span, machine_line, span

from imdrive.config.scenario import Scenario
from imdrive.run.simulate import simulate

VARIANTS = {
    "off": [],
    "paper": ["compensator.enabled=true", "compensator.t_on_s=0.0"],
    "injection": [
        "compensator.enabled=true",
        "compensator.t_on_s=0.0",
        "compensator.gain_E_per_Wb=1000",
        "compensator.gain_DE_per_Wb=1000",
        "compensator.G_CR_ohm=0.02",
        "injection.amplitude_A=0.5",
        "injection.frequency_Hz=2.0",
    ],
}


def measure(repeat: int) -> dict:
    out = {}
    for name, overrides in VARIANTS.items():
        sc = Scenario.read("sensorless", overrides)
        simulate(sc)  # compile or load the kernels
        times = [simulate(sc).wall_time_s for _ in range(repeat)]
        med = statistics.median(times)
        out[name] = {
            "times_s": times,
            "simulated_s": sc.simulation.t_end_s,
            "median_s": med,
            "min_s": min(times),
            "real_time_factor": sc.simulation.t_end_s / med,
        }
    # the minimum is the least disturbed run on a shared machine: overhead from minima
    base = out["off"]["min_s"]
    for name in ("paper", "injection"):
        out[name]["overhead_pct"] = 100.0 * (out[name]["min_s"] / base - 1.0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--json", metavar="PATH")
    args = ap.parse_args()
    print(machine_line())
    res = measure(args.repeat)
    print("sensorless preset, 3 s, kernel wall time; overhead from the fastest runs")
    for name, r in res.items():
        ov = f"overhead {r['overhead_pct']:+.1f} %" if "overhead_pct" in r else ""
        rtf = factor_span(r["simulated_s"], r["times_s"])
        print(f"  {name:<10} {span(r['times_s'], 'ms', 1e3):>38}  {rtf:>10} real time  {ov}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(res, f, indent=2)


if __name__ == "__main__":
    main()
