"""The accuracy table of docs/commissioning.md is the rendering of
docs/data/commissioning-accuracy.csv (``python -m imdrive.commission.accuracy``)."""

from __future__ import annotations

from imdrive.commission import accuracy


def test_commissioning_accuracy_table_is_the_rendering_of_the_csv():
    assert accuracy.main(["--check"]) == 0, (
        "docs/commissioning.md is stale: run 'python -m imdrive.commission.accuracy'"
    )


def test_check_fails_on_an_edited_table(tmp_path):
    page = tmp_path / "c.md"
    text = accuracy.DOC.read_text(encoding="utf-8")
    page.write_text(text.replace("| R1_ohm | 3 % |", "| R1_ohm | 4 % |", 1), encoding="utf-8")
    assert accuracy.main(["--check", "--path", str(page)]) == 1
