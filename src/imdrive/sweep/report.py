"""The interactive HTML report of a sweep store (``report.html`` beside ``runs.parquet``).

The sweep's heatmaps (the same ones as the PNGs of :mod:`imdrive.sweep.figures`: one figure
per heatmap, its panels in the same rows x cols grid, each cell's value written in it, tick
labels at the axis values, the title saying what a cell aggregates) with the values on hover,
the outcome counts, each metric's range over the runs, the axes and the sweep file, on the
page of :func:`imdrive.run.report.html_page` (one self-contained file, offline).
"""

from __future__ import annotations

import html
import math
from pathlib import Path

import numpy as np

from imdrive._io import atomic_path
from imdrive.errors import ConfigError
from imdrive.run.metrics import lost_control_check, lost_control_rule
from imdrive.run.report import html_page, html_table
from imdrive.run.status import verdict_counts
from imdrive.sweep.figures import (
    CMAP_PLAIN,
    CMAP_SIGNED,
    NONE_FINITE,
    NONE_FINITE_TEXT,
    SIGNED_METRICS,
    _levels,
    _tiny,
    aggregation_text,
    axis_label,
    cell_text,
    colour_range,
    heat_grid,
    panel_selections,
    plotly_scale,
)
from imdrive.sweep.spec import Heatmap, Sweep, _build_one_axis


def heatmap_plot(sweep: Sweep, df, h: Heatmap, div: str) -> dict:
    """One heatmap as a plotly.js figure: a grid of panels (``rows`` x ``cols``, as the PNG),
    the value written in each cell, tick labels at the axis values, a shared colour scale.

    Parameters
    ----------
    sweep : Sweep
        The sweep (its axes give the levels).
    df : pandas.DataFrame
        Its table.
    h : Heatmap
        Which axes, metric, panels and aggregation.
    div : str
        The id of the figure's element.

    Returns
    -------
    dict
        ``{"div", "data", "layout", "height"}`` for :func:`imdrive.run.report.html_page`.
    """
    signed = h.value in SIGNED_METRICS
    zr = colour_range(df[h.value], signed)
    scale = plotly_scale(CMAP_SIGNED if signed else CMAP_PLAIN)  # the PNGs' colours
    rows = [axis_label(v) for v in _levels(sweep, h.rows)] if h.rows else [None]
    cols = [axis_label(v) for v in _levels(sweep, h.cols)] if h.cols else [None]
    nr, nc = len(rows), len(cols)
    panels = panel_selections(sweep, df, h)
    tiny = _tiny(df[h.value].to_numpy(dtype=float))
    digits = _digits(df[h.value].to_numpy(dtype=float), tiny)
    gx, gy = 0.06, 0.12 if nr > 1 else 0.0
    w, ht = (0.9 - gx * (nc - 1)) / nc, (1.0 - gy * (nr - 1)) / nr
    data, annotations = [], []
    layout: dict = {
        "title": {
            "text": html.escape(f"{h.value}: {aggregation_text(sweep, h)}; {NONE_FINITE_TEXT}"),
            "font": {"size": 14},
        },
        "margin": {"l": 80, "r": 20, "t": 60, "b": 60},
        "plot_bgcolor": NONE_FINITE,
    }
    hover = f"{h.x} = %{{x}}<br>{h.y} = %{{y}}<br>{h.value} = %{{{{V}}:.4g}}<extra></extra>"
    for k, (title, sel) in enumerate(panels):
        r, c = divmod(k, nc)
        ax = "" if k == 0 else str(k + 1)
        x0 = c * (w + gx)
        top = 1.0 - r * (ht + gy)
        kind = "linear" if sweep.random else "category"
        layout[f"xaxis{ax}"] = {
            "domain": [x0, x0 + w], "anchor": f"y{ax}", "type": kind,
            "title": {"text": h.x if r == nr - 1 else ""}, "automargin": True,
        }  # fmt: skip
        layout[f"yaxis{ax}"] = {
            "domain": [top - ht, top], "anchor": f"x{ax}", "type": kind,
            "title": {"text": h.y if c == 0 else ""}, "automargin": True,
        }  # fmt: skip
        colour = {
            "colorscale": scale,
            "showscale": k == 0,
            "colorbar": {"title": {"text": h.value}, "x": 0.92},
        }
        if sweep.random:
            trace = {
                "type": "scatter", "mode": "markers",
                "x": sel[h.x].tolist(), "y": sel[h.y].tolist(),
                "marker": {"color": sel[h.value].astype(float).tolist(), "size": 8,
                           "cmin": zr[0], "cmax": zr[1], **colour},
                "hovertemplate": hover.replace("{V}", "marker.color"),
            }  # fmt: skip
        else:
            xs, ys, Z = heat_grid(sweep, sel, h)
            trace = {
                "type": "heatmap",
                "x": [axis_label(v) for v in xs],
                "y": [axis_label(v) for v in ys],
                "z": Z.tolist(),
                "text": cell_texts(Z, tiny, digits),
                "texttemplate": "%{text}",
                "hoverongaps": False,
                "hovertemplate": hover.replace("{V}", "z"),
                "zmin": zr[0],
                "zmax": zr[1],
                **colour,
            }
        trace.update({"xaxis": f"x{ax}", "yaxis": f"y{ax}"})
        data.append(trace)
        if title:
            annotations.append({
                "text": html.escape(title), "xref": "paper", "yref": "paper",
                "x": x0 + w / 2, "y": top, "xanchor": "center", "yanchor": "bottom",
                "showarrow": False,
            })  # fmt: skip
    layout["annotations"] = annotations
    ny = 1 if sweep.random else len(_levels(sweep, h.y))
    row_px = max(260, 26 * ny + 110)
    return {"div": div, "data": data, "layout": layout, "height": row_px * nr + 90}


def _digits(values, tiny: float) -> int:
    """Significant digits of the cell texts: two (:func:`cell_text`, as the PNGs), more (up to
    four) when two would print distinct values as the same number."""
    v = values[np.isfinite(values)]
    distinct = len(np.unique(v))
    for d in (2, 3, 4):
        if len({_text(x, tiny, d) for x in v}) >= min(distinct, 4):
            return d
    return 4


def _text(v: float, tiny: float, digits: int) -> str:
    if digits == 2 or not np.isfinite(v) or abs(v) < tiny or abs(v) >= 1e4:
        return cell_text(v, tiny)
    return f"{v:.{digits}g}"


def cell_texts(Z, tiny: float, digits: int = 2) -> list[list[str]]:
    """The text of each cell of ``Z`` (:func:`_digits` significant digits; ``""``: no value)."""
    return [[_text(float(v), tiny, digits) for v in row] for row in Z]


def lost_control_note(sweep: Sweep) -> str:
    """What "lost control" means in this sweep: the bound of
    :func:`~imdrive.config.perunit.lost_control_rpm` (``simulation.lost_control_rpm``, by
    default twice the rated slip of the run's machine, at least 1 % of its rated speed) and
    ``simulation.lost_control_s``, per value of each axis that changes them."""
    base = sweep.scenario(0)
    per_axis = []
    bounds = {lost_control_check(base)}
    for a in sweep.axes:
        here = {}
        for v in a.points():
            try:
                here[v] = lost_control_check(_build_one_axis(sweep, a, v))
            except ConfigError:  # listed as failing by the sweep's validation
                continue
        bounds |= set(here.values())
        if len(set(here.values())) > 1:
            per_axis += [
                f"{a.name} = {v}: {b * 30 / math.pi:.3g} rpm for {t:.3g} s"
                for v, (b, t) in here.items()
            ]
    if len(bounds) == 1:
        return lost_control_rule(base).capitalize() + "."
    return (
        "Loss of control: the speed farther from its reference than the run's bound for its "
        "duration (simulation.lost_control_rpm, lost_control_s; by default twice the rated slip "
        "of the run's machine, at least 1 % of its rated speed): " + "; ".join(per_axis) + "."
    )


def _metric_rows(df) -> list[tuple[str, object]]:
    """Each numeric column's finite range over the runs: ``min / median / max (n finite)``."""
    rows = []
    for col in df.columns:
        vals = df[col]
        if vals.dtype.kind not in "fiu":
            continue
        v = vals.to_numpy(dtype=float)
        v = v[np.isfinite(v)]
        if v.size == 0:
            rows.append((col, "no finite value"))
            continue
        rows.append(
            (
                col,
                f"{v.min():.5g} / {np.median(v):.5g} / {v.max():.5g} ({v.size} of {len(vals)})",
            )
        )
    return rows


def _axis_text(sweep: Sweep, axis) -> str:
    """An axis's values; for a random sweep their range or distinct values (not every draw)."""
    if not sweep.random:
        return ", ".join(axis_label(v) for v in axis.points())
    vals = list(axis.values)
    distinct = sorted(set(vals), key=str)
    if len(distinct) <= 12:
        return "drawn from " + ", ".join(str(v) for v in distinct)
    nums = np.asarray(vals, dtype=float)
    return f"{len(vals)} draws in [{nums.min():.6g}, {nums.max():.6g}]"


def sweep_report(sweep: Sweep, df) -> str:
    """The interactive report of a sweep, as HTML text.

    Parameters
    ----------
    sweep : Sweep
        The sweep as run.
    df : pandas.DataFrame
        Its table (``runs.parquet``).

    Returns
    -------
    str
        A self-contained HTML page.
    """
    n_div = int(df["diverged"].sum()) if "diverged" in df else 0
    n_lc = int(df["lost_control"].sum()) if "lost_control" in df else 0
    n_fail = int((df["status"] < 0).sum()) if "status" in df else 0
    notes = [html.escape(sweep.description)] if sweep.description else []
    shape = "random" if sweep.random else " x ".join(str(n) for n in sweep.shape)
    notes.append(
        html.escape(
            f"{len(df)} runs ({shape}): {n_div} diverged, {n_lc} lost control, {n_fail} could "
            "not be built. Hover a cell for its values; drag to zoom, double-click to reset."
        )
    )
    notes.append(html.escape(lost_control_note(sweep)))
    notes.append(html.escape(f"status (imdrive.run.status): {verdict_counts(df)}"))
    figures = [heatmap_plot(sweep, df, h, f"heatmap-{i}") for i, h in enumerate(sweep.heatmaps)]
    if not figures:
        notes.append("The sweep declares no heatmaps.")
    tables = [
        html_table(
            [("runs", len(df)), ("diverged", n_div), ("lost control", n_lc), ("failed", n_fail)]
            + _metric_rows(df),
            "summary (min / median / max over the finite values)",
            header=("column", "value"),
        ),
        html_table(
            [(a.name, _axis_text(sweep, a)) for a in sweep.axes],
            "axes",
            header=("axis", "values"),
        ),
    ]
    if sweep.source:
        tables.append(
            "<details><summary>sweep file</summary><pre>"
            f"{html.escape(sweep.source)}</pre></details>"
        )
    return html_page(f"imdrive sweep: {sweep.name}", notes, figures, {}, tables)


def write_sweep_report(sweep: Sweep, df, path) -> Path:
    """Write :func:`sweep_report` to ``path`` atomically; return the path."""
    path = Path(path)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(sweep_report(sweep, df), encoding="utf-8")
    return path
