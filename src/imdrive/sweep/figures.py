"""Heatmaps of a sweep's table: a metric over two axes, optionally in rows x cols panels.

A grid sweep aggregates the other axes (``mean``, ``min``, ``max`` or ``absmax``) into an image
per panel; a random sweep scatters its runs. Signed errors use a diverging colour map centred
on zero.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imdrive._io import atomic_path
from imdrive.sweep.spec import Heatmap, Sweep

SIGNED_METRICS = ("speed_error_rpm", "speed_est_error_rpm", "R2_error_pct")


def _aggregate(series, how: str):
    if how == "absmax":
        return series.abs().max()
    return getattr(series, how)()


def heatmap_figure(sweep: Sweep, df, h: Heatmap):
    """One heatmap (or a grid of them: ``rows`` x ``cols`` panels) of a metric over two axes.

    Parameters
    ----------
    sweep : Sweep
        The sweep (its axes give the levels).
    df : pandas.DataFrame
        The sweep's table, one row per run.
    h : Heatmap
        Which axes, metric, panels and aggregation.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not attached to pyplot).
    """
    from matplotlib.figure import Figure

    rows = _levels(sweep, h.rows) if h.rows else [None]
    cols = _levels(sweep, h.cols) if h.cols else [None]
    fig = Figure(figsize=(3.6 * len(cols) + 1.2, 3.0 * len(rows) + 0.8), layout="constrained")
    axs = fig.subplots(len(rows), len(cols), squeeze=False)
    signed = h.value in SIGNED_METRICS
    vmin, vmax = colour_range(df[h.value], signed)
    style = {"cmap": "RdBu_r" if signed else "viridis", "vmin": vmin, "vmax": vmax}
    mappable = None
    for r, rv in enumerate(rows):
        for c, cv in enumerate(cols):
            ax = axs[r, c]
            sel = df
            if h.rows:
                sel = sel[sel[h.rows] == rv]
            if h.cols:
                sel = sel[sel[h.cols] == cv]
            ax.set_facecolor("0.85")
            draw = _scatter_panel if sweep.random else _image_panel
            mappable = draw(ax, sweep, sel, h, style)
            ax.set_xlabel(h.x)
            ax.set_ylabel(h.y)
            title = ", ".join(
                f"{n} = {_fmt(v)}" for n, v in ((h.rows, rv), (h.cols, cv)) if n is not None
            )
            if title:
                ax.set_title(title, fontsize=9)
    if mappable is not None:
        fig.colorbar(mappable, ax=axs, label=h.value, shrink=0.9)
    agg = "" if sweep.random else f" ({h.agg} over the other axes; grey: none finite)"
    fig.suptitle(f"{sweep.name}: {h.value}{agg}", fontsize=10)
    return fig


def _levels(sweep: Sweep, name: str) -> list:
    """The distinct values of axis ``name``, in order."""
    return next(a for a in sweep.axes if a.name == name).points()


def colour_range(values, signed: bool) -> tuple[float, float]:
    """``(vmin, vmax)`` over the finite values; symmetric about 0 for a signed metric."""
    vals = values.to_numpy(dtype=float)
    finite = vals[np.isfinite(vals)]
    if finite.size:
        vmax = float(np.max(np.abs(finite))) if signed else float(finite.max())
        vmin = -vmax if signed else float(finite.min())
    else:
        vmin, vmax = -1.0, 1.0
    if vmin == vmax:
        vmin, vmax = vmin - 1.0, vmax + 1.0
    return vmin, vmax


def _scatter_panel(ax, sweep: Sweep, sel, h: Heatmap, style: dict):
    """A random sweep's panel: one dot per run."""
    return ax.scatter(sel[h.x], sel[h.y], c=sel[h.value], s=18, **style)


def panel_selections(sweep: Sweep, df, h: Heatmap) -> list[tuple[str, object]]:
    """``[(title, rows of df)]``: one panel per (``rows``, ``cols``) pair of axis values."""
    rows = _levels(sweep, h.rows) if h.rows else [None]
    cols = _levels(sweep, h.cols) if h.cols else [None]
    out = []
    for rv in rows:
        for cv in cols:
            sel = df
            if h.rows:
                sel = sel[sel[h.rows] == rv]
            if h.cols:
                sel = sel[sel[h.cols] == cv]
            title = ", ".join(
                f"{n} = {_fmt(v)}" for n, v in ((h.rows, rv), (h.cols, cv)) if n is not None
            )
            out.append((title, sel))
    return out


def heat_grid(sweep: Sweep, sel, h: Heatmap) -> tuple[list, list, np.ndarray]:
    """``(xs, ys, Z)``: the metric ``h.value`` of the runs ``sel`` aggregated (``h.agg``) over
    the other axes, ``Z[iy, ix]`` at axis values ``ys[iy]``, ``xs[ix]`` (NaN: none finite)."""
    xs, ys = _levels(sweep, h.x), _levels(sweep, h.y)
    g = sel.groupby([h.y, h.x], sort=False)[h.value].agg(lambda s, how=h.agg: _aggregate(s, how))
    Z = np.full((len(ys), len(xs)), np.nan)
    for (yv, xv), v in g.items():
        Z[ys.index(yv), xs.index(xv)] = v
    return xs, ys, Z


def _image_panel(ax, sweep: Sweep, sel, h: Heatmap, style: dict):
    """A grid sweep's panel: the metric aggregated over the other axes, one cell per point."""
    xs, ys, Z = heat_grid(sweep, sel, h)
    image = ax.imshow(
        np.ma.masked_invalid(Z), origin="lower", aspect="auto", interpolation="nearest", **style
    )
    ax.set_xticks(range(len(xs)), [_fmt(v) for v in xs], rotation=45)
    ax.set_yticks(range(len(ys)), [_fmt(v) for v in ys])
    if Z.size <= 100:
        for (iy, ix), v in np.ndenumerate(Z):
            if np.isfinite(v):
                ax.text(ix, iy, _cell(v), ha="center", va="center", fontsize=6)
    return image


def _cell(v: float) -> str:
    a = abs(v)
    return f"{v:.0f}" if a >= 100 else f"{v:.1f}" if a >= 1 else f"{v:.2f}"


def _fmt(v) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def save_heatmaps(sweep: Sweep, df, folder: Path) -> list[Path]:
    """Write every heatmap of ``sweep`` as a PNG.

    Parameters
    ----------
    sweep : Sweep
        The sweep (its ``heatmaps``).
    df : pandas.DataFrame
        The sweep's table, one row per run.
    folder : str or pathlib.Path
        Folder to write into (created).

    Returns
    -------
    list of pathlib.Path
        The PNG files written.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for h in sweep.heatmaps:
        fig = heatmap_figure(sweep, df, h)
        extra = "".join(f"_by_{n}" for n in (h.rows, h.cols) if n)
        name = f"{h.value}__{h.y}_vs_{h.x}{extra}.png".replace("/", "_")
        path = folder / name
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=110, format="png")
        written.append(path)
    return written
