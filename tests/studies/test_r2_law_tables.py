"""The generated table of R2 tracking with each estimator (docs/estimators.md,
imdrive.studies.r2_law_tables): a reduced fresh run reproduces its stored rows, and the
rendering counts what the rows say."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from imdrive.studies import r2_law_tables as study

DATA = Path(__file__).resolve().parents[2] / "docs" / "data" / "r2_law_estimators.csv"
KEYS = ["machine", "estimator", "speed_pu", "load_pu", "R1_ratio", "R2_ratio"]


@pytest.mark.slow
def test_reduced_run_reproduces_the_stored_rows():
    t = study.measure(
        machines=("aalto-2.2kw",), points=((0.2, 1.0),), ests=("mras", "afo"), r2=(0.8,), r1=(1.0,)
    )
    both = t.merge(pd.read_csv(DATA), on=KEYS, suffixes=("", "_stored"), validate="one_to_one")
    assert len(both) == 2
    for _, row in both.iterrows():
        assert row["verdict"] == row["verdict_stored"]
        for col in ("R2_error_pct", "speed_error_rpm"):
            assert row[col] == pytest.approx(row[col + "_stored"], rel=1e-6, abs=1e-9), (
                "run 'python -m imdrive.studies.doctables --run r2-law-estimators'"
            )


def test_the_table_counts_its_rows():
    df = pd.read_csv(DATA)
    assert set(df["estimator"]) >= {"mras", "smo-mras", "reactive-mras", "afo", "ekf"}
    assert len(df) == len(study.MACHINES) * len(study.POINTS) * 4 * df["estimator"].nunique()
    lines = study.render(df)
    mras = [x for x in lines if x.startswith("| mras | 1 |")][0]
    g = df[(df.estimator == "mras") & (df.R1_ratio == 1.0)]
    assert f"{int((g.R2_error_pct.abs() <= study.GOAL_PCT).sum())} of {len(g)}" in mras
