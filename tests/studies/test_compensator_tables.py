"""The 50-1400 rpm section of docs/envelope.md (imdrive.studies.compensator_tables): the
classification of the envelope sweep's runs on hand-made rows, the stored data against the
grid and the page's claims, and the gains study measured again (slow)."""

from __future__ import annotations

from itertools import product
from pathlib import Path

import numpy as np
import pandas as pd

from imdrive.studies import compensator_tables as ct

DATA = Path(__file__).resolve().parents[2] / "docs" / "data"


def _row(variant, speed=150.0, load=6.0, r2=1.0, r1=1.0, **kw):
    base = {
        "run": 0,
        "speed_rpm": speed,
        "load_Nm": load,
        "R2_ratio": r2,
        "R1_ratio": r1,
        "variant": variant,
        "diverged": False,
        "lost_control": False,
        "convergence_time_s": 5.0,
        "R2_error_pct": 0.1,
        "speed_error_rpm": 0.05,
    }
    return {**base, **kw}


def test_classify_region_and_goal():
    rows = [
        _row("uncompensated"),  # the point (150, 6, 1.0) is stable
        _row("uncompensated", load=-12.0, lost_control=True),  # (150, -12, 1.0) is not
        _row("injection"),  # inside, within goal
        _row("injection", r2=1.2, convergence_time_s=14.5),  # converged too late
        _row("injection", r2=0.8, R2_error_pct=-2.5),  # R2_hat off
        _row("injection", r2=0.8, r1=1.0, speed_error_rpm=1.2),  # speed off
        _row("injection", load=-12.0),  # outside the region: not counted
    ]
    c = ct.classify(pd.DataFrame(rows))
    assert list(c["inside"]) == [True, False, True, True, True, True, False]
    assert list(c["ok"]) == [True, False, True, False, False, False, True]
    lines = ct.render_compensators(pd.DataFrame(rows))
    injection = next(line for line in lines if line.startswith("| injection"))
    assert "**1 of 4 (25.0 %)**" in injection
    assert "**not met**" in lines[-1] and "outside: 150 rpm, −12 N m" in lines[-1]
    misses = ct.render_misses(pd.DataFrame(rows))
    assert len(misses) == 2 + 2  # header, rule, (150, 6, 0.8) and (150, 6, 1.2)
    assert "| 150 | +6 | 0.8 | 1, 1 | −2.5 … +0.1 |" in misses[2]


def test_stored_sweep_covers_the_grid_and_meets_the_goal():
    from imdrive.sweep import load_sweep

    df = pd.read_csv(DATA / "envelope_compensators.csv")
    sweep = load_sweep(ct.SWEEP)
    assert len(df) == int(np.prod([len(a.values) for a in sweep.axes]))
    for axis in sweep.axes:
        assert sorted(set(df[axis.name])) == sorted(set(axis.values)), axis.name
    c = ct.classify(df)
    inj = c[(c["variant"] == "injection") & c["inside"]]
    assert inj["ok"].mean() >= ct.SHARE_GOAL  # the page says: met
    # the uncompensated drive is within goal only where it starts right (the page's prose)
    unc = c[(c["variant"] == "uncompensated") & c["ok"]]
    assert np.allclose(unc["R2_ratio"], 1.0)


def test_stored_off_grid_points_are_off_the_grid():
    from imdrive.sweep import load_sweep

    df = pd.read_csv(DATA / "envelope_off_grid.csv")
    sweep = load_sweep(ct.SWEEP)
    for axis in sweep.axes[:4]:
        assert not set(df[df["variant"] == "injection"][axis.name]) & set(axis.values)
    g = ct.OFF_GRID
    assert len(df) == len(list(product(*g.values()))) + len(g["speed_rpm"]) * len(
        g["load_Nm"]
    ) * len(g["R1_ratio"])
