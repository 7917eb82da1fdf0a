"""``report.html``: the interactive report of a run (:mod:`imdrive.run.report`)."""

from __future__ import annotations

from pathlib import Path

from imdrive.run.formats import OutputFormat


def _write(res, folder: Path) -> None:
    from imdrive.run.report import write_run_report

    write_run_report(res, folder / "report.html")


FORMAT = OutputFormat(
    name="report",
    key="report",
    files=("report.html",),
    write=_write,
    description="interactive linked plots of the columns (min/max-decimated), the summary and "
    "the scenario in one self-contained file that works offline",
    order=50,
)
