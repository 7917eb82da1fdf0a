"""A heatmap's cell of value 0 is not drawn in the colour that means "none finite" (issue 39:
a signed metric's 0 was RdBu_r's near-white centre in the PNGs, within 0.11 of the 0.85 grey
of an empty cell, and plotly.js's grey RdBu centre in the HTML report), in the PNG and in the
HTML report."""

from __future__ import annotations

import itertools

import matplotlib as mpl
import numpy as np
import pandas as pd
import pytest

from imdrive.sweep import figures as sweep_figures
from imdrive.sweep import parse_sweep
from imdrive.sweep.report import heatmap_plot

#: smallest RGB distance (0..sqrt 3) between an empty cell and any cell with a value
DISTINCT = 0.3

SWEEP = """
name = "zeros"
base = "sensorless"

[axes]
R2_ratio = [0.8, 1.0, 1.2]
speed_rpm = [300, 900]

[[heatmap]]
x = "R2_ratio"
y = "speed_rpm"
value = "{value}"
"""


def _sweep_and_frame(value: str):
    """A 3 x 2 grid: the metric 0 at R2_ratio 1 (the finding of a well-tuned drive), no finite
    value at (1.2, 900 rpm), and values on both sides of 0 elsewhere (a signed metric)."""
    sweep = parse_sweep(SWEEP.format(value=value))
    axes = {a.name: a.points() for a in sweep.axes}
    rows = [dict(zip(axes, p, strict=True)) for p in itertools.product(*axes.values())]
    df = pd.DataFrame(rows)
    sign = (lambda v: v) if value in sweep_figures.SIGNED_METRICS else abs
    df[value] = [
        np.nan if (r["R2_ratio"], r["speed_rpm"]) == (1.2, 900) else sign(20 * (r["R2_ratio"] - 1))
        for r in rows
    ]
    return sweep, sweep.heatmaps[0], df


def _rgb(colour) -> np.ndarray:
    return np.asarray(mpl.colors.to_rgb(colour))


def _plotly_colour(scale: list, t: float) -> np.ndarray:
    """The colour of plotly's linear interpolation of ``scale`` at ``t`` in [0, 1]."""
    ts = [s[0] for s in scale]
    rgb = np.array([[int(c) / 255 for c in s[1][4:-1].split(",")] for s in scale])
    return np.array([np.interp(t, ts, rgb[:, k]) for k in range(3)])


def test_no_colour_of_either_map_is_near_the_empty_cells_grey():
    none = _rgb(sweep_figures.NONE_FINITE)
    for name in (sweep_figures.CMAP_SIGNED, sweep_figures.CMAP_PLAIN):
        colours = mpl.colormaps[name](np.linspace(0.0, 1.0, 1001))[:, :3]
        assert np.linalg.norm(colours - none, axis=1).min() >= DISTINCT, name


@pytest.mark.parametrize("value", ["speed_error_rpm", "speed_ripple_rpm"])
def test_a_zero_cell_of_the_png_is_not_grey(value):
    sweep, h, df = _sweep_and_frame(value)
    fig = sweep_figures.heatmap_figure(sweep, df, h)
    ax = next(a for a in fig.axes if a.images)
    image = ax.images[0]
    Z = np.ma.filled(image.get_array(), np.nan)
    assert np.isnan(Z).sum() == 1 and (Z == 0.0).sum() == 2
    empty = _rgb(ax.get_facecolor())
    assert np.allclose(empty, _rgb(sweep_figures.NONE_FINITE))
    zero = np.asarray(image.cmap(image.norm(0.0))[:3])
    assert np.linalg.norm(zero - empty) >= DISTINCT
    assert "dark grey: none finite" in fig._suptitle.get_text()


@pytest.mark.parametrize("value", ["speed_error_rpm", "speed_ripple_rpm"])
def test_a_zero_cell_of_the_html_report_is_not_grey(value):
    sweep, h, df = _sweep_and_frame(value)
    plot = heatmap_plot(sweep, df, h, "h")
    trace = plot["data"][0]
    scale = trace["colorscale"]
    assert isinstance(scale, list)  # not plotly.js's named RdBu, grey at its centre
    t0 = (0.0 - trace["zmin"]) / (trace["zmax"] - trace["zmin"])
    empty = _rgb(plot["layout"]["plot_bgcolor"])
    assert np.linalg.norm(_plotly_colour(scale, t0) - empty) >= DISTINCT
    # the report's colours are the PNG's, stop for stop
    cmap = mpl.colormaps[sweep_figures.CMAP_SIGNED if value == "speed_error_rpm" else "viridis"]
    for t in np.linspace(0.0, 1.0, 21):
        assert np.allclose(_plotly_colour(scale, t), cmap(t)[:3], atol=0.03), t


def test_the_stability_map_uses_the_same_grey():
    """The stability map draws Re(s) on RdBu_r too: its 0 is the map's near-white centre."""
    from imdrive.stability.plots import NO_STEADY_STATE

    assert NO_STEADY_STATE == sweep_figures.NONE_FINITE
