"""The figures show the finding: the steady e_d0 bias is visible in a zoomed
panel, the compensator's switch-on is marked, every quantity has one unit across the figures
(flux in mWb, no hidden multiplier), legends say what a signal is, and heatmap annotations are
sized to their cells in a colour that contrasts with them."""

import itertools
import re
from pathlib import Path

import matplotlib as mpl
import numpy as np
import pandas as pd
import pytest

from imdrive.config.scenario import Scenario
from imdrive.run import plots
from imdrive.run.simulate import simulate
from imdrive.studies import paper
from imdrive.sweep import figures as sweep_figures
from imdrive.sweep import load_sweep, parse_sweep
from imdrive.sweep.spec import Heatmap

FIGURES = Path(__file__).parents[2] / "docs" / "figures"


@pytest.fixture(scope="module")
def fig5():
    return simulate(Scenario.read("paper-fig5"))


@pytest.fixture(scope="module")
def injection():
    return simulate(Scenario.read("injection-fig6", ["simulation.t_end_s=6.0"]))


def _all_figures(fig5, injection):
    """Every figure the package draws from a run or from the reproduction's tables."""
    figs = []
    for res in (fig5, injection):
        figs += [
            plots.speed_figure(res),
            plots.torque_figure(res),
            plots.currents_figure(res),
            plots.estimator_figure(res),
            plots.compensation_figure(res),
            plots.result_figure(res),
            plots.result_figure(res, signals=["e_d0_Wb", "flux_Wb", "R2_hat_ohm"]),
        ]
    figs.append(paper.figure_e_d0_vs_ratio(pd.read_csv(FIGURES / "e_d0_vs_R2_ratio.csv")))
    figs.append(paper.figure_e_d0_vs_Ts(pd.read_csv(FIGURES / "e_d0_vs_Ts.csv")))
    figs.append(paper.figure_e_d0_vs_R1(pd.read_csv(FIGURES / "e_d0_vs_R1.csv")))
    figs.append(paper.figure_injection_signal(pd.read_csv(FIGURES / "injection_signal.csv")))
    w = fig5.window(2.5)
    figs.append(
        paper.figure_transients(
            pd.DataFrame({"R2_ratio": 1.2, **{k: w[k] for k in paper.TRANSIENT_COLUMNS}})
        )
    )
    figs.append(paper.figure_thermal(injection))
    figs.append(paper.figure_detuning_law())
    for f in figs:
        f.draw_without_rendering()
    return figs


@pytest.fixture(scope="module")
def all_figures(fig5, injection):
    """:func:`_all_figures`, drawn once for the tests that only read their labels and legends
    (drawing them is 20-30 s on a loaded machine)."""
    return _all_figures(fig5, injection)


def _zoom_axes(fig):
    return next(ax for ax in fig.axes if ax.get_ylabel().startswith("flux error, zoom"))


def test_e_d0_zoom_panel_is_scaled_by_the_steady_state_not_the_transient(fig5):
    s = fig5.signals
    t_on = fig5.scenario.compensator.t_on_s
    steady = s["e_d0_Wb"][s["time_s"] >= t_on] * 1e3  # mWb
    transient = np.max(np.abs(s["e_d0_Wb"])) * 1e3
    scale = np.max(np.abs(steady))
    assert transient > 30 * scale  # the start-up transient would flatten the bias to a line
    fig = plots.compensation_figure(fig5)
    lo, hi = _zoom_axes(fig).get_ylim()
    assert lo <= np.percentile(steady, 1) and hi >= np.percentile(steady, 99)
    assert hi - lo <= 2.0 * scale  # within a factor of the steady values (zero included)
    assert hi - lo >= scale
    # the whole-run panel keeps the transient's scale
    lo0, hi0 = fig.axes[0].get_ylim()
    assert hi0 - lo0 > 0.9 * transient


def test_estimator_figure_zooms_the_flux_errors_too(fig5):
    fig = plots.estimator_figure(fig5)
    s = fig5.signals
    steady = s["e_d0_Wb"][s["time_s"] >= plots.steady_start(fig5)] * 1e3
    lo, hi = _zoom_axes(fig).get_ylim()
    assert hi - lo < 0.05 * np.ptp(s["e_d0_Wb"] * 1e3)
    assert lo <= steady.min()


def test_compensator_switch_on_is_marked_on_every_panel(fig5, injection):
    for res in (fig5, injection):
        fig = plots.compensation_figure(res)
        t_on = res.scenario.compensator.t_on_s
        for ax in fig.axes:
            xs = [ln.get_xdata() for ln in ax.get_lines() if len(ln.get_xdata()) == 2]
            assert any(np.all(np.asarray(x) == t_on) for x in xs), ax.get_ylabel()
        texts = [t.get_text() for t in fig.axes[0].texts]
        assert any("compensator on" in t for t in texts), texts


def test_no_switch_on_mark_without_a_compensator():
    res = simulate(Scenario.read("sensorless-detuned", ["simulation.t_end_s=3.0"]))
    fig = plots.estimator_figure(res)
    assert not any("compensator on" in t.get_text() for ax in fig.axes for t in ax.texts)


def test_zoom_limits_are_robust_and_include_zero():
    v = np.r_[np.full(1000, -0.37), 40.0]  # one spike
    lo, hi = plots.zoom_limits(v)
    assert lo < -0.37 and 0.0 < hi < 0.1
    assert plots.zoom_limits([]) == (-1.0, 1.0)
    assert plots.zoom_limits(np.zeros(5)) == (-1.0, 1.0)


UNIT = re.compile(r"\(([^()]*)\)\s*$")
#: the one unit each quantity is drawn in; a label naming another unit of it fails
ONE_UNIT = {"flux": "mWb", "resistance": "Ω", "speed": "rpm", "torque": "N m", "current": "A"}
OTHER_UNITS = {
    "flux": ("Wb", "uWb", "µWb", "μWb"),
    "resistance": ("ohm", "mohm", "mΩ"),
    "speed": ("rad/s", "Hz"),
    "torque": ("Nm", "kN m"),
    "current": ("mA",),
}


def _labels(figs):
    for fig in figs:
        for ax in fig.axes:
            for axis in (ax.xaxis, ax.yaxis):
                yield ax, axis, axis.get_label().get_text()


@pytest.mark.slow
def test_one_unit_per_quantity_across_the_figures(all_figures):
    figs = all_figures
    seen: dict[str, list] = {}
    for ax, axis, label in _labels(figs):
        m = UNIT.search(label)
        if not m:
            continue
        unit = m.group(1)
        for quantity, units in OTHER_UNITS.items():
            assert unit not in units, f"{label!r}: {quantity} is drawn in {ONE_UNIT[quantity]}"
            if unit == ONE_UNIT[quantity]:
                seen.setdefault(quantity, []).append(label)
        if unit == "mWb":
            # the label is the whole truth: no "1e-3" multiplier or offset beside the axis
            assert axis.get_offset_text().get_text() == "", label
            if axis.get_scale() == "linear":
                lo, hi = ax.get_ylim() if axis is ax.yaxis else ax.get_xlim()
                assert max(abs(lo), abs(hi)) < 5000.0, label  # never a 35 000-unit axis
    assert set(seen) == set(ONE_UNIT)  # every quantity was met at least once
    assert len(seen["flux"]) >= 15 and "flux linkage (mWb)" in seen["flux"]


COLUMN_NAME = re.compile(r"^[a-zA-Z0-9]+(_[a-zA-Z0-9]+)*_(rpm|Nm|A|Wb|ohm|V|C|rad|s)$")


@pytest.mark.slow
def test_legends_say_what_a_signal_is(all_figures):
    entries = set()
    for fig in all_figures:
        for ax in fig.axes:
            leg = ax.get_legend()
            if leg is not None:
                entries |= {t.get_text() for t in leg.get_texts()}
    for text in entries:
        assert not COLUMN_NAME.match(text), text
        assert "sin(" not in text and text not in ("e_d0", "i_d", "R2 estimate", "actual")
    for want in ("estimated speed (MRAS)", "rotor-resistance estimate R̂2", "actual R2 (plant)"):
        assert want in entries


# ---------------------------------------------------------------------------------------------
# heatmaps


def test_text_colour_contrasts_with_every_colour_of_the_maps():
    for name in ("RdBu_r", "viridis"):
        cmap = mpl.colormaps[name]
        for x in np.linspace(0.0, 1.0, 101):
            rgba = cmap(x)
            text = (0.0, 0.0, 0.0) if sweep_figures.text_colour(rgba) == "black" else (1, 1, 1)
            assert sweep_figures.contrast_ratio(rgba, text) >= 4.5, (name, x)
    assert sweep_figures.text_colour(mpl.colormaps["RdBu_r"](0.0)) == "white"  # dark blue
    assert sweep_figures.text_colour((0.97, 0.97, 0.97, 1.0)) == "black"


def test_cell_text_has_few_digits_and_no_negative_zero():
    cases = {
        18921.0: "19k",
        1891.2: "1891",
        14.5: "14",
        -29.2: "-29",
        7.43: "7.4",
        0.434: "0.43",
        -0.061: "-0.061",
        0.0: "0",
        -0.0004: "0",
    }
    for v, want in cases.items():
        assert sweep_figures.cell_text(v, tiny=0.001) == want, v
    assert sweep_figures.cell_text(float("nan")) == ""
    assert sweep_figures.cell_text(-1e-7) == "-1e-07"


def _sweep_frame(sweep, h: Heatmap, fn):
    axes = {a.name: a.points() for a in sweep.axes}
    rows = [dict(zip(axes, p, strict=True)) for p in itertools.product(*axes.values())]
    df = pd.DataFrame(rows)
    df[h.value] = [fn(r) for r in rows]
    return df


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_heatmap_annotations_are_sized_to_cells_and_contrast():
    sweep = load_sweep("detuning-map")
    h = sweep.heatmaps[0]
    df = _sweep_frame(
        sweep, h, lambda r: 30.0 * (r["R2_ratio"] - 1.0) * r["load_Nm"] / 12.0 * 2.5 - 0.001
    )
    fig = sweep_figures.heatmap_figure(sweep, df, h)
    texts = [t for ax in fig.axes for t in ax.texts]
    assert len(texts) == 9 * 7 * 9  # every cell of the 3 x 3 panels of 9 x 7
    assert all(t.get_text() != "-0" and "-0.00" not in t.get_text() for t in texts)
    sizes = {t.get_fontsize() for t in texts}
    assert len(sizes) == 1 and sweep_figures.MIN_FONTSIZE <= sizes.pop() <= 10
    image_axes = [ax for ax in fig.axes if ax.images]
    for ax in image_axes:
        im = ax.images[0]
        Z = im.get_array()
        for t in ax.texts:
            ix, iy = (int(round(c)) for c in t.get_position())
            cell = im.cmap(im.norm(Z[iy, ix]))
            text = mpl.colors.to_rgba(t.get_color())
            assert sweep_figures.contrast_ratio(cell, text) >= 4.5
    # the darkest cells (both ends of RdBu_r) get white text, the pale middle black
    colours = {t.get_text(): t.get_color() for t in texts}
    assert colours["-30"] == "white" and colours["30"] == "white" and colours["0"] == "black"


DENSE = """
name = "dense"
base = "sensorless"

[axes]
R2_ratio = { min = 0.6, max = 1.4, num = 80 }
speed_rpm = { min = 50, max = 1500, num = 60 }

[[heatmap]]
x = "R2_ratio"
y = "speed_rpm"
value = "speed_error_rpm"
"""


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_heatmap_cells_too_small_are_not_annotated():
    sweep = parse_sweep(DENSE)
    h = sweep.heatmaps[0]
    df = _sweep_frame(sweep, h, lambda r: r["R2_ratio"])
    fig = sweep_figures.heatmap_figure(sweep, df, h)  # 80 x 60 cells in under 4 inches
    assert fig.axes[0].images and not fig.axes[0].texts
    assert sweep_figures.annotation_fontsize(40.0, 20.0, 4) == pytest.approx(9.0)
    assert sweep_figures.annotation_fontsize(8.0, 5.0, 4) is None
