"""The whole-rating envelope of docs/envelope.md is generated: its tables are the rendering of
docs/figures/envelope-full.csv (``python -m imdrive.studies.envelope``; ``--run`` re-measures it
with the envelope-full sweep), and a reduced grid of that sweep runs end to end, every run's
status agreeing with its numbers."""

from __future__ import annotations

import pandas as pd
import pytest

from imdrive.studies import envelope


@pytest.mark.slow  # 1.5 s or more on 2 cores (2.2 s measured 2026-11-29)
def test_envelope_tables_are_the_rendering_of_the_csv():
    text = envelope.DOC_PATH.read_text(encoding="utf-8")
    assert text == envelope.page(text, pd.read_csv(envelope.CSV_PATH)), (
        "docs/envelope.md is stale: run 'python -m imdrive.studies.envelope'"
    )
    assert envelope.main(["--check"]) == 0


def test_check_fails_on_an_edited_table(tmp_path):
    page = tmp_path / "p.md"
    text = envelope.DOC_PATH.read_text(encoding="utf-8")
    marker = envelope.BEGIN.format("goals")
    a = text.index(marker) + len(marker)
    page.write_text(text[:a] + "\n| edited |" + text[a:], encoding="utf-8")
    assert envelope.main(["--check", "--path", str(page)]) == 1


def test_stored_runs_cover_the_whole_rating_and_none_is_unflagged():
    df = envelope.classify(pd.read_csv(envelope.CSV_PATH))
    assert df["speed_pu"].min() == -2.0 and df["speed_pu"].max() == 2.0
    assert df["speed_pu"].abs().min() * envelope.rated_speed_rpm() == pytest.approx(20, abs=0.1)
    assert set(df["load_pu_available"]) == {-1.0, -0.5, 0.0, 0.5, 1.0}
    assert set(df["inverter"]) == {"ideal", "bridge"} and set(df["thermal"]) == {"constant", "ramp"}
    assert not df["unflagged"].any()


@pytest.mark.slow  # 8 closed-loop runs of 38 s, half of them on the switching bridge
def test_reduced_grid_runs_end_to_end(tmp_path):
    sweep = envelope.reduced_sweep(tmp_path / "reduced.toml")
    df = envelope.run(
        tmp_path / "store", sweep_file=str(sweep), csv=tmp_path / "e.csv", figures=tmp_path / "f"
    )
    assert len(df) == 8
    stored = pd.read_csv(tmp_path / "e.csv")
    assert list(stored.columns) == list(envelope.KEEP)
    png = "verdict_ok__speed_pu_vs_load_pu_available_by_inverter_by_thermal.png"
    assert (tmp_path / "f" / png).is_file()
    c = envelope.classify(stored)
    assert not c["unflagged"].any(), c[c["unflagged"]].to_string()
    # twice the rated speed: R2 is not observable there on today's code, and the rows say so
    high = c[(c["speed_pu"] == -2.0) & c["stable"]]
    for _, row in high.iterrows():
        if abs(row["R2_error_pct"]) > 2.0:
            assert row["verdict"] in ("frozen", "held", "R2-off"), row.to_dict()
    text = "\n".join(sum(envelope.tables(stored).values(), []))
    assert "| ideal | constant | 2 |" in text
    # and the 8 runs are those of the stored whole-rating sweep: the page is not stale against
    # the code (the generated tables above are only checked against the CSV)
    keys = ["inverter", "thermal", "speed_pu", "load_pu_available", "R2_ratio", "R1_ratio"]
    full = pd.read_csv(envelope.CSV_PATH)
    both = stored.merge(full, on=keys, suffixes=("", "_stored"), validate="one_to_one")
    assert len(both) == 8
    for _, row in both.iterrows():
        assert row["verdict"] == row["verdict_stored"], (
            f"{row[keys].to_dict()}: {row['verdict']} now, {row['verdict_stored']} stored: run "
            "'python -m imdrive.studies.envelope --run'"
        )
        for col in ("R2_error_pct", "speed_error_rpm"):
            a, b = float(row[col]), float(row[col + "_stored"])
            if not (pd.isna(a) and pd.isna(b)):
                assert a == pytest.approx(b, rel=1e-6, abs=1e-9), (row[keys].to_dict(), col, a, b)
