"""The injection compensator near its blind band, with and without the gating.

When the stator frequency is near the injection frequency the detected signal collapses into
the fuzzy table's dead zone (docs/paper-reproduction.md, "Gating and the blind band"). At five
operating points, from R̂2(0) = 1.15 R2 and 0.85 R2 (16 s runs, compensator from 4 s, the
``injection-fig5`` preset with the clamps widened to 0.3-1.5 Ω), :func:`blind_band_runs`
measures the final R̂2 error without the gating (``compensator.gating = false``: one fixed
injection frequency, no freezing) and with it (the default), and the speed error at the end.
"""

from __future__ import annotations

import pandas as pd

from imdrive.analysis import foc_operating_point
from imdrive.config.scenario import Scenario
from imdrive.run.batch import simulate_batch

#: (speed, rpm; load, N m) of the table: near the band (f_e about 2 Hz) and away from it
OPERATING_POINTS = ((54.0, 1.5), (45.0, 3.0), (100.0, -6.0), (150.0, 12.0), (1000.0, 12.0))
#: R̂2(0)/R2 of the runs
RATIOS = (1.15, 0.85)


def _scenario(speed: float, torque: float, ratio: float, gating: bool) -> Scenario:
    R2 = Scenario.read("injection-fig5").machine.R2_ohm
    return Scenario.read(
        "injection-fig5",
        [
            f"control.speed_ref_rpm={{initial=0,changes=[{{at=0.5,to={speed},over=1.0}}]}}",
            f"load.torque_Nm={{initial=0,changes=[{{at=2.0,to={torque}}}]}}",
            f"estimator.R2_ohm={ratio * R2}",
            # clamps in ohm whatever R2_hat(0) is (deprecated spellings: R2_min_ratio is of
            # R2_hat(0), which this study varies)
            "compensator.R2_min_ohm=0.3",
            "compensator.R2_max_ohm=1.5",
            f"compensator.gating={str(gating).lower()}",
            "simulation.t_end_s=16.0",
            "output.figures=false",
        ],
    )


def blind_band_runs(points=OPERATING_POINTS, ratios=RATIOS) -> pd.DataFrame:
    """One row per operating point, starting error and gating (on / off): the final R̂2 error,
    %, and the speed error at the end, rpm (means over the last 0.5 s), with the stator
    frequency of the operating point, Hz (the steady state of :func:`foc_operating_point`)."""
    cases = [
        (speed, torque, ratio, gating)
        for speed, torque in points
        for ratio in ratios
        for gating in (False, True)
    ]
    batch = simulate_batch([_scenario(*c) for c in cases], window_s=0.5)
    machine = Scenario.read("injection-fig5").machine
    rows = []
    for (speed, torque, ratio, gating), (_, m) in zip(cases, batch.metrics.iterrows(), strict=True):
        rows.append(
            {
                "speed_rpm": speed,
                "load_Nm": torque,
                "f_e_Hz": foc_operating_point(machine, speed, torque).f_Hz,
                "R2_ratio_initial": ratio,
                "gating": gating,
                "diverged": bool(m["diverged"]),
                "R2_error_final_pct": m["R2_error_pct"],
                "speed_error_rpm": m["speed_error_rpm"],
            }
        )
    return pd.DataFrame(rows)
