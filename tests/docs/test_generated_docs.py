"""Result tables of docs/paper-reproduction.md are generated: the compensation tables are the
rendering of docs/figures/compensation.csv (``python -m imdrive.studies.docs``), and that file
is what ``imdrive paper`` computes today (the estimator tables: tests/test_bench_docs.py; the
scenario keys: test_config_schema.py)."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from imdrive.studies import docs


def test_paper_reproduction_tables_are_the_rendering_of_the_csv():
    text = docs.DOC_PATH.read_text(encoding="utf-8")
    assert text == docs.page(text, pd.read_csv(docs.CSV_PATH)), (
        "docs/paper-reproduction.md is stale: run 'python -m imdrive.studies.docs'"
    )
    assert docs.main(["--check"]) == 0


def test_check_fails_on_an_edited_table(tmp_path):
    page = tmp_path / "p.md"
    text = docs.DOC_PATH.read_text(encoding="utf-8")
    edited = text.replace("+14.53 → ", "+14.55 → ", 1)  # a speed error of the injection table
    assert edited != text
    page.write_text(edited)
    assert docs.main(["--check", "--path", str(page)]) == 1


@pytest.mark.slow
def test_compensation_csv_is_what_the_code_computes():
    from imdrive.studies.paper import compensation_table

    stored = pd.read_csv(docs.CSV_PATH).set_index("preset")
    fresh = compensation_table().set_index("preset")
    assert list(fresh.index) == list(stored.index)
    for col in stored.columns:
        for preset in stored.index:
            a, b = fresh.loc[preset, col], stored.loc[preset, col]
            if isinstance(b, str):
                assert a == b
            elif not (math.isnan(float(a)) and math.isnan(float(b))):
                assert float(a) == pytest.approx(float(b), rel=1e-6, abs=1e-12), (
                    f"{preset} {col}: {a} now, {b} stored: run 'imdrive paper --out out/paper'"
                    " and copy its files to docs/figures"
                )
