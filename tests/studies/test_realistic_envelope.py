"""The generated table of the recommended drive on the realistic drive (docs/envelope.md,
imdrive.studies.realistic_envelope): a reduced fresh run reproduces its stored rows, the
rendering counts what the rows say, and the grid's drive is the realistic presets'."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from imdrive.config.scenario import Scenario
from imdrive.studies import realistic_envelope as study
from imdrive.sweep.spec import load_sweep

DATA = Path(__file__).resolve().parents[2] / "docs" / "data" / "realistic_envelope.csv"
KEYS = ["machine", "speed_pu", "load_pu", "R2_ratio", "seed"]


@pytest.mark.slow
def test_reduced_run_reproduces_the_stored_rows():
    # the low-speed cells from 0.8 R2, unloaded and motoring the rated torque, on two machines
    # (on the presets' noise seed: R2-unsettled on Table IV unloaded, +2.4 % over the final
    # window; the three others ok), and one cell of another seed
    t = study.measure(
        machines=("paper-table-iv", "krause-3hp"), speeds=(0.2,), loads=(0.0, 1.0),
        ratios=(0.8,), seeds=(1,),
    )  # fmt: skip
    t = pd.concat(
        [
            t,
            study.measure(
                machines=("krause-3hp",), speeds=(0.2,), loads=(-1.0,), ratios=(0.8,), seeds=(3,)
            ),
        ]
    )
    both = t.merge(pd.read_csv(DATA), on=KEYS, suffixes=("", "_stored"), validate="one_to_one")
    assert len(both) == 5
    for _, row in both.iterrows():
        assert row["verdict"] == row["verdict_stored"]
        for col in ("R2_error_pct", "R2_error_window_pct", "speed_error_rpm"):
            assert row[col] == pytest.approx(row[col + "_stored"], rel=1e-6, abs=1e-9), (
                "run 'python -m imdrive.studies.doctables --run realistic-envelope'"
            )


def test_the_table_counts_its_rows():
    df = pd.read_csv(DATA)
    n = len(study.SPEEDS_PU) * len(study.LOADS_PU) * len(study.R2_RATIOS)
    assert len(df) == len(study.MACHINES) * n * len(study.SEEDS)
    lines = study.render(df)
    assert len(lines) == 2 + len(study.MACHINES) * len(study.SPEEDS_PU)
    g = df[(df.machine == "paper-table-iv") & (df.speed_pu == 0.2)]
    row = [x for x in lines if x.startswith("| paper-table-iv | 0.2 ")][0]
    g1 = g[g.seed == 1]  # the presets' seed, then the range over the seeds
    per_seed = g.groupby("seed")["verdict"].apply(lambda v: int((v == "ok").sum()))
    assert f"| {int((g1.verdict == 'ok').sum())} of {len(g1)} |" in row
    assert f"| {per_seed.min()}–{per_seed.max()} |" in row
    # no run lost control, and none reports ok with R2_hat outside the 2 % goal
    assert not df["lost_control"].astype(bool).any()
    ok = df[df.verdict == "ok"]
    assert (ok[["R2_error_pct", "R2_error_window_pct"]].abs() <= 2.0).all().all()


def test_the_grid_runs_the_realistic_presets_drive():
    """Each of :data:`REALISTIC`'s settings is the realistic presets' own value."""
    for preset in ("injection-fig5-realistic", "sensorless-realistic"):
        real = Scenario.read(preset, [])
        mine = Scenario.read(study.PRESET, list(study.REALISTIC))
        for ov in study.REALISTIC:
            path = ov.split("=")[0].split(".")
            a, b = real, mine
            for p in path:
                a, b = getattr(a, p), getattr(b, p)
            assert a == b, (preset, ov)


GRID = DATA.with_name("realistic_envelope_grid.csv")


@pytest.mark.slow
def test_reduced_sweep_grid_run_reproduces_the_stored_rows():
    # the grid's one miss (the Aalto machine at 0.3 regenerating from 0.8 R2) and the paper's
    # variant's worst cell of the sweep (Table IV at the rated speed and load from 1.2 R2)
    t = pd.concat(
        [
            study.measure(machines=("aalto-2.2kw",), speeds=(0.3,), loads=(-1.0,),
                          ratios=(0.8,), seeds=(1,)),
            study.measure(machines=("paper-table-iv",), speeds=(1.0,), loads=(1.0,),
                          ratios=(1.2,), seeds=(1,)),
        ]
    )  # fmt: skip
    both = t.merge(pd.read_csv(GRID), on=KEYS, suffixes=("", "_stored"), validate="one_to_one")
    assert len(both) == 2
    for _, row in both.iterrows():
        assert row["verdict"] == row["verdict_stored"]
        for col in ("R2_error_pct", "R2_error_window_pct", "speed_error_rpm"):
            assert row[col] == pytest.approx(row[col + "_stored"], rel=1e-6, abs=1e-9), (
                "run 'python -m imdrive.studies.doctables --run realistic-envelope-grid'"
            )


def test_the_sweep_grid_table_is_the_sweeps_grid_on_every_machine():
    df = pd.read_csv(GRID)
    g = study.SWEEP_GRID
    assert len(df) == len(study.MACHINES) * len(g["speeds"]) * len(g["loads"]) * len(g["ratios"])
    assert set(df["seed"]) == set(g["seeds"]) == {1}
    # the envelope-realistic sweep's speeds, rpm, are these per-unit speeds of Table IV's
    axes = {a.name: a.values for a in load_sweep("envelope-realistic").axes}
    rated = df.loc[df.machine == "paper-table-iv", "rated_speed_rpm"].iloc[0]
    assert [round(s * rated) for s in g["speeds"]] == list(axes["speed_rpm"])
    assert list(axes["R2_ratio"]) == list(g["ratios"])
    lines = study.render(df)
    assert len(lines) == 2 + len(study.MACHINES) * len(g["speeds"])
    assert "seeds" not in lines[0]  # one seed: no range column
    # no run lost control; none reports ok with R2_hat outside the 2 % goal; Table IV all ok
    assert not df["lost_control"].astype(bool).any()
    ok = df[df.verdict == "ok"]
    assert (ok[["R2_error_pct", "R2_error_window_pct"]].abs() <= 2.0).all().all()
    assert (df.loc[df.machine == "paper-table-iv", "verdict"] == "ok").all()
