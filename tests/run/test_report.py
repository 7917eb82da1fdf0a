"""The interactive HTML reports (``report.html``): decimation, contents, size, and rendering in a
real headless browser (Chromium; skipped with a message where none is installed)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from data.browser import (
    FLOAT_NOISE,
    assert_nonblank,
    assert_rendered,
    render,
    render_and_screenshot,
    tick_labels,
)

import imdrive as im
from imdrive.run.report import minmax_decimate, run_report


@pytest.fixture(scope="module")
def short_run():
    sc = im.Scenario.read("injection-fig5").with_overrides({"simulation.t_end_s": 0.6})
    return im.simulate(sc)


def test_decimation_keeps_every_peak():
    rng = np.random.default_rng(1)
    n = 100_003
    t = np.arange(n) * 1e-4
    y = rng.standard_normal(n)
    y[54_321] = 50.0
    y[777] = -40.0
    td, out, b = minmax_decimate(t, {"y": y}, max_points=1000)
    assert b > 1 and len(td) <= 1000 + 2 and len(out["y"]) == len(td)
    assert out["y"].max() == 50.0 and out["y"].min() == -40.0
    assert np.all(np.diff(td) >= 0) and td[0] == t[0] and td[-1] == t[-1]
    # the peak sits within one bucket of its true time
    assert abs(td[np.argmax(out["y"])] - t[54_321]) <= b * 1e-4
    short, out2, b2 = minmax_decimate(t[:500], {"y": y[:500]}, max_points=1000)
    assert b2 == 1 and np.array_equal(out2["y"], y[:500])


def test_report_written_by_default_and_skipped_on_request(tmp_path, short_run):
    short_run.save(tmp_path / "a", figures=False, csv=False)
    html = (tmp_path / "a" / "report.html").read_text(encoding="utf-8")
    assert "http://" not in html.replace("http://www.w3.org", "")  # nothing to fetch
    assert "https://" not in html.split('id="plotly-gz"')[0]
    for text in (
        "speed",
        "rotor-resistance estimate",
        "e_d0 detected synchronously",
        '"mWb"',  # flux in mWb, as in every figure
        "scenario as run",
        "summary",
    ):
        assert text in html
    off = short_run.scenario.with_overrides({"output.report": False})
    short_run.scenario = off
    try:
        short_run.save(tmp_path / "b", figures=False, csv=False)
    finally:
        short_run.scenario = off.with_overrides({"output.report": True})
    assert not (tmp_path / "b" / "report.html").exists()
    # an earlier result with a report is an imdrive result: replaced without --force
    short_run.save(tmp_path / "a", figures=False, csv=False)


def test_full_rate_14s_report_is_small():
    sc = im.Scenario.read("injection-fig5").with_overrides({"simulation.log_every": 1})
    res = im.simulate(sc)
    assert len(res.time_s) > 100_000
    size = len(run_report(res).encode("utf-8"))
    assert size < 5e6, f"{size / 1e6:.2f} MB"


@pytest.mark.slow
def test_run_report_renders_every_panel_with_a_time_axis_and_a_flux_zoom(tmp_path):
    """The run report renders in a browser (it had a test of its own on a 0.6 s run: the same
    page with fewer points, one browser start more), every panel with its time axis."""
    sc = im.Scenario.read("injection-fig5").with_overrides({"simulation.t_end_s": 6.0})
    res = im.simulate(sc)
    path = tmp_path / "report.html"
    path.write_text(run_report(res), encoding="utf-8")
    html = path.read_text()
    assert "flux error, steady-state zoom" in html
    dom, pixels = render_and_screenshot(path, tmp_path / "run.png")
    assert_rendered(dom, ["signals"])
    n_panels = len([labels for labels in tick_labels(dom, "y") if labels])
    x_axes = [labels for labels in tick_labels(dom, "x") if labels]
    assert n_panels >= 8 and len(x_axes) == n_panels, (n_panels, len(x_axes))
    for labels in x_axes:  # each panel's time axis runs over the run, in round numbers
        assert labels[0] == "0" and not any(FLOAT_NOISE.search(x) for x in labels), labels
    assert dom.count(">time (s)<") == n_panels
    assert_nonblank(pixels)


SWEEP = """
name = "tiny"
description = "report test: 2 x 2 short runs, one variant diverging"
base = "sensorless"
chunk_size = 8
window_s = 0.1

[set]
simulation.t_end_s = 0.3
control.speed_ref_rpm = { initial = 0, changes = [{ at = 0.05, to = 600, over = 0.15 }] }

[axes]
R2_ratio = [0.8, 1.2]
speed_rpm = [300, 900]

[axes.variant]
stable = {}
unstable = { control.current_kp = 150, "inverter.Vdc_V" = 1e5 }

[[heatmap]]
x = "R2_ratio"
y = "speed_rpm"
value = "speed_error_rpm"
cols = "variant"
"""


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_sweep_report_renders_in_a_browser(tmp_path):
    from imdrive.sweep import load_sweep, run_sweep

    f = tmp_path / "tiny.toml"
    f.write_text(SWEEP)
    store = tmp_path / "store"
    run_sweep(load_sweep(str(f)), store, progress=False, figures=False)
    page = store / "report.html"
    html = page.read_text(encoding="utf-8")
    assert "variant = stable" in html and "variant = unstable" in html
    assert "speed_error_rpm = %{z:.4g}" in html  # the value on hover
    assert_rendered(render(page), ["heatmap-0"])


NOISY_SWEEP = """
name = "noisy-axes"
base = "sensorless"
window_s = 0.1

[set]
simulation.t_end_s = 0.3
control.speed_ref_rpm = { initial = 0, changes = [{ at = 0.05, to = 600, over = 0.15 }] }

[axes]
R2_ratio = { min = 0.7, max = 1.3, num = 7 }
speed_rpm = [300, 900]
R1_ratio = [0.9, 1.1]
variant = { plain = {}, fast = { control.speed_bandwidth_Hz = 10 } }

[[heatmap]]
x = "R2_ratio"
y = "speed_rpm"
value = "speed_error_rpm"
cols = "variant"
"""


@pytest.mark.slow
def test_sweep_report_is_a_facet_grid_with_values_and_round_labels(tmp_path):
    from imdrive.sweep import load_sweep, run_sweep

    f = tmp_path / "noisy.toml"
    f.write_text(NOISY_SWEEP)
    store = tmp_path / "store"
    sweep = load_sweep(str(f))
    assert any("99999" in repr(v) for v in sweep.axes[0].points())  # linspace float noise
    run_sweep(sweep, store, progress=False, figures=False)
    page = store / "report.html"
    html = page.read_text(encoding="utf-8")
    # the title says what a cell is: the mean over the axis not drawn, not "the other axes"
    assert "speed_error_rpm: mean over R1_ratio (2 runs per cell)" in html
    assert "over the other axes" not in html
    dom, pixels = render_and_screenshot(page, tmp_path / "sweep.png", height=1400)
    assert_rendered(dom, ["heatmap-0"])
    assert dom.count('class="heatmaplayer') == 2  # the two panels of one figure
    labels = [x for axis in tick_labels(dom, "x") for x in axis]
    assert "0.8" in labels and "1.3" in labels
    assert not any(FLOAT_NOISE.search(x) for x in labels), labels
    # a value written in every cell of both panels (2 panels x 7 x 2 cells)
    cells = re.findall(r'<text[^>]*data-notex="1"[^>]*>(-?[\d.]+k?)</text>', dom)
    assert len(cells) == 28, cells
    assert_nonblank(pixels)


def test_reports_state_the_machine_derived_lost_control_bound(short_run):
    """The run report and the sweep report state the loss-of-control bound the run used: twice
    the rated slip of its machine (158 rpm on Table IV, 190 rpm on Krause's 50 hp machine)."""
    from imdrive.config.perunit import lost_control_rpm
    from imdrive.sweep.report import lost_control_note
    from imdrive.sweep.spec import parse_sweep

    page = run_report(short_run)
    bound = lost_control_rpm(short_run.scenario)
    assert f"more than {bound:.3g} rpm" in page and "158 rpm" in page
    assert "rated slip" in page and "200 rpm" not in page
    one = parse_sweep('base = "sensorless"\n[axes]\nR2_ratio = [1.0, 1.1]\n')
    assert "more than 158 rpm from its reference for 1 s" in lost_control_note(one)
    two = parse_sweep(
        'base = "sensorless"\n[axes]\n"machine.preset" = ["paper-table-iv", "krause-50hp"]\n'
    )
    note = lost_control_note(two)
    big = lost_control_rpm(im.Scenario.read("sensorless", ["machine.preset=krause-50hp"]))
    assert "paper-table-iv: 158 rpm" in note and f"krause-50hp: {big:.3g} rpm" in note


def test_data_limits_fit_a_constant_signal_and_a_moving_one():
    from imdrive.run.plots import data_limits

    assert data_limits(np.full(50, 0.145)) == pytest.approx((0.13775, 0.15225))
    lo, hi = data_limits(np.linspace(0.0, 1500.0, 50))
    assert lo == pytest.approx(-75.0) and hi == pytest.approx(1575.0)
    assert data_limits(np.zeros(3)) == (-1.0, 1.0)
    assert data_limits([np.nan, np.inf]) == (-1.0, 1.0)


def test_run_report_r2_panel_fits_its_data(short_run):
    """Issue 39: the report's R2 panel spanned -0.5 .. 1 ohm for an R2 of 0.145 ohm (plotly.js
    autoranges a constant v as v - 1 .. v + 1). Every panel's y-range now fits its data."""
    from imdrive.run.report import _run_figure

    fig, arrays, _ = _run_figure(short_run, 2000)
    layout = fig["layout"]
    titles = [a["text"] for a in layout["annotations"]]
    i = next(k for k, t in enumerate(titles) if "rotor resistance" in t)
    lo, hi = layout["yaxis" if i == 0 else f"yaxis{i + 1}"]["range"]
    r2 = np.concatenate([short_run.signals["R2_ohm"], short_run.signals["R2_hat_ohm"]])
    assert lo <= r2.min() and hi >= r2.max()
    assert 0.0 < lo and hi - lo <= 0.25 * np.abs(r2).max() + (r2.max() - r2.min())
    for k in range(len(titles)):  # every panel has a finite range that holds its traces
        lo, hi = layout["yaxis" if k == 0 else f"yaxis{k + 1}"]["range"]
        assert np.isfinite([lo, hi]).all() and lo < hi


def test_plotly_js_is_compressed_once_and_kept_in_the_cache(tmp_path, monkeypatch):
    """The report's plotly.js is compressed once per plotly version and read back after (it
    was 0.3 s of every warm run); the kept text unpacks to plotly.js itself."""
    import base64
    import gzip

    import plotly
    from plotly.offline import get_plotlyjs

    from imdrive.run import report

    monkeypatch.setenv("IMDRIVE_CACHE_DIR", str(tmp_path))
    report._plotly_js_gz_b64.cache_clear()
    first = report._plotly_js_gz_b64()
    kept = tmp_path / f"plotly-{plotly.__version__}.b64"
    assert kept.read_text("ascii") == first
    assert gzip.decompress(base64.b64decode(first)) == get_plotlyjs().encode("utf-8")
    kept.write_text("c3RhbXA=", "ascii")  # a stamp: the second process reads, never compresses
    report._plotly_js_gz_b64.cache_clear()
    assert report._plotly_js_gz_b64() == "c3RhbXA="
    report._plotly_js_gz_b64.cache_clear()
