"""R2 tracking with every registered speed estimator: the recommended preset
(``injection-robust``, the model-based R2 law) with ``control.speed_feedback`` set to each
estimator, at operating points in per-unit of two machines, from R̂2(0) 0.8 and 1.2 R2, with
R̂1(0) as the preset has it (1.1 R1) and exact.

The MRAS family hands the detection its flux error and adapts R1 online; the others (the AFO,
the EKF) get the detection's own flux error (:mod:`imdrive.kernels.flux_detector`) and do not
adapt R1, so their R̂1 error enters R̂2 through the voltage model: the R̂1 = R1 rows tell
that part apart.

``python -m imdrive.studies.doctables --run r2-law-estimators`` measures it again (80 runs,
about a minute) and rewrites its table in docs/estimators.md.
"""

from __future__ import annotations

import warnings

import pandas as pd

from imdrive.config.rated import rated_point
from imdrive.config.registry import ESTIMATOR_SETTINGS
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning
from imdrive.run.batch import simulate_batch
from imdrive.studies.doctable import DocTable, register

#: Machines: the paper's and the Aalto laboratory machine (other rated slip and size).
MACHINES = ("paper-table-iv", "aalto-2.2kw")
#: ``(speed, load)`` in per-unit of the machine's rated speed and torque (negative load:
#: regenerating): half speed and load, low speed at rated load, regenerating at 0.1 speed,
#: rated speed and load.
POINTS = ((0.5, 0.5), (0.2, 1.0), (0.1, -1.0), (1.0, 1.0))
#: Starting R̂2(0)/R2, and R̂1(0)/R1: the preset's 1.1, and exact.
R2_RATIOS = (0.8, 1.2)
R1_RATIOS = (1.1, 1.0)
#: R̂2 within this of R2 at the end counts as tracked, %.
GOAL_PCT = 2.0


def estimators() -> tuple[str, ...]:
    """The registered estimators of the package (a user's plug-in is not imported here)."""
    return tuple(ESTIMATOR_SETTINGS)


def scenarios(machines=MACHINES, points=POINTS, ests=None, r2=R2_RATIOS, r1=R1_RATIOS):
    """The grid's scenarios and a row describing each."""
    rows, scs = [], []
    for m in machines:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConfigWarning)
            base = Scenario.read("injection-robust", [f'machine.preset="{m}"'])
        rp = rated_point(base.machine)
        for est in ests or estimators():
            for speed, load in points:
                n, T = speed * rp.speed_rpm, load * rp.torque_Nm
                for a in r1:
                    for b in r2:
                        ov = [
                            f'control.speed_feedback="{est}"',
                            f"estimator.R1_ratio={a}",
                            f"estimator.R2_ratio={b}",
                            "control.speed_ref_rpm={initial=0, changes=[{at=0.5, "
                            f"to={n:.6g}, over=1.0}}]}}",
                            f"load.torque_Nm={{initial=0, changes=[{{at=2.0, to={T:.6g}}}]}}",
                        ]
                        with warnings.catch_warnings():
                            warnings.simplefilter("ignore", ConfigWarning)
                            scs.append(base.with_overrides(ov))
                        rows.append((m, est, speed, load, a, b))
    cols = ["machine", "estimator", "speed_pu", "load_pu", "R1_ratio", "R2_ratio"]
    return scs, pd.DataFrame(rows, columns=cols)


def measure(**grid) -> pd.DataFrame:
    """Run the grid: its rows with the run's R̂2 error at the end, %, the speed error, rpm,
    whether control was lost and the verdict."""
    scs, table = scenarios(**grid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        res = simulate_batch(scs, errors="record")
    m = res.metrics
    for col in ("R2_error_pct", "speed_error_rpm", "lost_control", "verdict"):
        table[col] = m[col].to_numpy()
    return table


def render(df: pd.DataFrame) -> list[str]:
    """Per estimator and R̂1(0): the runs with R̂2 within :data:`GOAL_PCT` at the end, the
    worst R̂2 error and the runs that lost control."""
    out = [
        f"| estimator | R̂1(0)/R1 | R̂2 within {GOAL_PCT:g} % | worst R̂2 error | lost control "
        "| verdict ok |",
        "|---|---|---|---|---|---|",
    ]
    for est in dict.fromkeys(df["estimator"]):
        for a in sorted(df["R1_ratio"].unique(), reverse=True):
            g = df[(df["estimator"] == est) & (df["R1_ratio"] == a)]
            e = g["R2_error_pct"].abs()
            worst = g["R2_error_pct"].iloc[int(e.to_numpy().argmax())]
            n_in = int((e <= GOAL_PCT).sum())
            w = f"{worst:+.2f} %".replace("-", "−")
            out.append(
                f"| {est} | {a:g} | {n_in} of {len(g)} | {w} "
                f"| {int(g['lost_control'].astype(bool).sum())} "
                f"| {int((g['verdict'] == 'ok').sum())} |"
            )
    return out


register(
    DocTable("r2-law-estimators", "estimators.md", "data/r2_law_estimators.csv", render, measure)
)
