"""The interactive HTML report of a sweep store (``report.html`` beside ``runs.parquet``).

The sweep's heatmaps (the same ones as the PNGs of :mod:`imdrive.sweep.figures`, one plot per
panel) with the axis values and the metric on hover, the outcome counts, each metric's range
over the runs, the axes and the sweep file, on the page of :func:`imdrive.run.report.html_page`
(one self-contained file, offline).
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from imdrive._io import atomic_path
from imdrive.run.report import html_page, html_table
from imdrive.sweep.figures import SIGNED_METRICS, colour_range, heat_grid, panel_selections
from imdrive.sweep.spec import Heatmap, Sweep

#: Diverging scale for signed errors (plotly's RdBu: blue below zero, red above, as the PNGs'
#: matplotlib RdBu_r), sequential otherwise
SIGNED_SCALE = "RdBu"
PLAIN_SCALE = "Viridis"


def _panel_figure(sweep: Sweep, sel, h: Heatmap, div: str, title: str, zr) -> dict:
    signed = h.value in SIGNED_METRICS
    colour = {
        "colorscale": SIGNED_SCALE if signed else PLAIN_SCALE,
        "cmin" if sweep.random else "zmin": zr[0],
        "cmax" if sweep.random else "zmax": zr[1],
        "colorbar": {"title": {"text": h.value}},
    }
    hover = f"{h.x} = %{{x}}<br>{h.y} = %{{y}}<br>{h.value} = %{{{{V}}:.4g}}<extra></extra>"
    if sweep.random:
        trace = {
            "type": "scatter",
            "mode": "markers",
            "x": sel[h.x].tolist(),
            "y": sel[h.y].tolist(),
            "marker": {"color": sel[h.value].astype(float).tolist(), "size": 8, **colour},
            "hovertemplate": hover.replace("{V}", "marker.color"),
        }
    else:
        xs, ys, Z = heat_grid(sweep, sel, h)
        trace = {
            "type": "heatmap",
            "x": [str(v) for v in xs],
            "y": [str(v) for v in ys],
            "z": Z.tolist(),
            "hoverongaps": False,
            "hovertemplate": hover.replace("{V}", "z"),
            **colour,
        }
    agg = "" if sweep.random else f" ({h.agg} over the other axes)"
    head = f"{h.value}{agg}" + (f": {title}" if title else "")
    layout = {
        "title": {"text": html.escape(head), "font": {"size": 14}},
        "xaxis": {"title": {"text": h.x}, "type": "linear" if sweep.random else "category"},
        "yaxis": {"title": {"text": h.y}, "type": "linear" if sweep.random else "category"},
        "margin": {"l": 80, "r": 20, "t": 50, "b": 60},
        "plot_bgcolor": "#d9d9d9",
    }
    return {"div": div, "data": [trace], "layout": layout, "height": 420}


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
        return ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in axis.points())
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
    figures = []
    for i, h in enumerate(sweep.heatmaps):
        zr = colour_range(df[h.value], h.value in SIGNED_METRICS)
        for j, (title, sel) in enumerate(panel_selections(sweep, df, h)):
            figures.append(_panel_figure(sweep, sel, h, f"heatmap-{i}-{j}", title, zr))
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
