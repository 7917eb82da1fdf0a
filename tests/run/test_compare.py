"""``imdrive compare`` and ``compare()``: runs of a user's scenario on another machine side by
side (overlaid signals, metrics in one table, an HTML report that renders in a browser)."""

from __future__ import annotations

import pandas as pd
import pytest

import imdrive as im
from imdrive.cli import main
from imdrive.errors import ConfigError
from imdrive.run.compare import compare

OTHER_MACHINE = [
    'machine.preset="aalto-2.2kw"',
    "inverter.Vdc_V=560",  # a 400 V machine on a 400 V inverter
    "simulation.t_end_s=2.5",
]


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    sets = [a for s in OTHER_MACHINE for a in ("--set", s)]
    assert main(["run", "sensorless", *sets, "--out", str(root / "mras"), "-q"]) == 0
    ekf = ["--set", 'control.speed_feedback="ekf"']
    assert main(["run", "sensorless", *sets, *ekf, "--out", str(root / "ekf"), "-q"]) == 0
    return root / "mras", root / "ekf"


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_compare_command_writes_figure_metrics_and_report(two_runs, tmp_path):
    out = tmp_path / "cmp"
    assert main(["compare", *map(str, two_runs), "--out", str(out), "-q"]) == 0
    assert {p.name for p in out.iterdir()} == {"compare.png", "metrics.csv", "report.html"}
    m = pd.read_csv(out / "metrics.csv", index_col="metric")
    assert list(m.columns) == ["mras", "ekf"]
    # the metrics are each run's own: recomputed from the folders, they match the runs
    sc = im.Scenario.read("sensorless", OTHER_MACHINE)
    res = im.simulate(sc)
    assert float(m.loc["speed_error_rpm", "mras"]) == pytest.approx(
        res.metrics()["speed_error_rpm"], rel=1e-4, abs=1e-3
    )
    assert float(m.loc["R2_final_ohm", "ekf"]) == pytest.approx(sc.machine.R2_ohm)


def test_compare_in_python_overlays_and_names_the_runs(two_runs):
    cmp = compare(two_runs, labels=["MRAS", "EKF"], signals=["speed_rpm", "speed_est_rpm"])
    assert list(cmp.metrics.columns) == ["MRAS", "EKF"]
    fig = cmp.figure()
    assert len(fig.axes) == 2
    assert all(len(ax.lines) == 2 for ax in fig.axes)  # a line per run in each panel
    assert all(ax.get_xlabel() == "time (s)" for ax in fig.axes)
    assert len(cmp._repr_png_()) > 10_000


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_compare_report_renders_in_a_browser(two_runs, tmp_path):
    from data.browser import assert_rendered, render

    page = tmp_path / "report.html"
    page.write_text(compare(two_runs).report(), encoding="utf-8")
    html = page.read_text()
    assert "metrics side by side" in html
    assert_rendered(render(page), ["signals"])


def test_compare_rejects_a_folder_that_is_no_result(tmp_path):
    with pytest.raises(ConfigError, match="summary.json"):
        compare([tmp_path])
    assert main(["compare", str(tmp_path), "--out", str(tmp_path / "c")]) == 2
