"""Heatmaps of a sweep's table: a metric over two axes, optionally in rows x cols panels.

A grid sweep aggregates the other axes (``mean``, ``min``, ``max`` or ``absmax``) into an image
per panel; a random sweep scatters its runs. Signed errors use a diverging colour map centred
on zero.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imdrive.sweep.spec import Heatmap, Sweep

SIGNED_METRICS = ("speed_error_rpm", "speed_est_error_rpm", "R2_error_pct")


def _aggregate(series, how: str):
    if how == "absmax":
        return series.abs().max()
    return getattr(series, how)()


def heatmap_figure(sweep: Sweep, df, h: Heatmap):
    """One heatmap (or a grid of them: ``rows`` x ``cols`` panels) of a metric over two axes."""
    from matplotlib.figure import Figure

    def levels(name):
        a = next(a for a in sweep.axes if a.name == name)
        return a.points()

    rows = levels(h.rows) if h.rows else [None]
    cols = levels(h.cols) if h.cols else [None]
    fig = Figure(figsize=(3.6 * len(cols) + 1.2, 3.0 * len(rows) + 0.8), layout="constrained")
    axs = fig.subplots(len(rows), len(cols), squeeze=False)
    vals = df[h.value].to_numpy(dtype=float)
    finite = vals[np.isfinite(vals)]
    signed = h.value in SIGNED_METRICS
    if finite.size:
        vmax = float(np.max(np.abs(finite))) if signed else float(finite.max())
        vmin = -vmax if signed else float(finite.min())
    else:
        vmin, vmax = -1.0, 1.0
    if vmin == vmax:
        vmin, vmax = vmin - 1.0, vmax + 1.0
    cmap = "RdBu_r" if signed else "viridis"
    mappable = None
    for r, rv in enumerate(rows):
        for c, cv in enumerate(cols):
            ax = axs[r, c]
            sel = df
            if h.rows:
                sel = sel[sel[h.rows] == rv]
            if h.cols:
                sel = sel[sel[h.cols] == cv]
            title = ", ".join(
                f"{n} = {_fmt(v)}" for n, v in ((h.rows, rv), (h.cols, cv)) if n is not None
            )
            ax.set_facecolor("0.85")
            if sweep.random:
                mappable = ax.scatter(
                    sel[h.x], sel[h.y], c=sel[h.value], cmap=cmap, vmin=vmin, vmax=vmax, s=18
                )
                ax.set_xlabel(h.x)
                ax.set_ylabel(h.y)
            else:
                xs, ys = levels(h.x), levels(h.y)
                g = sel.groupby([h.y, h.x], sort=False)[h.value].agg(
                    lambda s, how=h.agg: _aggregate(s, how)
                )
                Z = np.full((len(ys), len(xs)), np.nan)
                for (yv, xv), v in g.items():
                    Z[ys.index(yv), xs.index(xv)] = v
                mappable = ax.imshow(
                    np.ma.masked_invalid(Z),
                    origin="lower",
                    aspect="auto",
                    cmap=cmap,
                    vmin=vmin,
                    vmax=vmax,
                    interpolation="nearest",
                )
                ax.set_xticks(range(len(xs)), [_fmt(v) for v in xs], rotation=45)
                ax.set_yticks(range(len(ys)), [_fmt(v) for v in ys])
                ax.set_xlabel(h.x)
                ax.set_ylabel(h.y)
                if Z.size <= 100:
                    for (iy, ix), v in np.ndenumerate(Z):
                        if np.isfinite(v):
                            ax.text(ix, iy, _cell(v), ha="center", va="center", fontsize=6)
            if title:
                ax.set_title(title, fontsize=9)
    if mappable is not None:
        fig.colorbar(mappable, ax=axs, label=h.value, shrink=0.9)
    agg = "" if sweep.random else f" ({h.agg} over the other axes; grey: none finite)"
    fig.suptitle(f"{sweep.name}: {h.value}{agg}", fontsize=10)
    return fig


def _cell(v: float) -> str:
    a = abs(v)
    return f"{v:.0f}" if a >= 100 else f"{v:.1f}" if a >= 1 else f"{v:.2f}"


def _fmt(v) -> str:
    return f"{v:g}" if isinstance(v, float) else str(v)


def save_heatmaps(sweep: Sweep, df, folder: Path) -> list[Path]:
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for h in sweep.heatmaps:
        fig = heatmap_figure(sweep, df, h)
        extra = "".join(f"_by_{n}" for n in (h.rows, h.cols) if n)
        name = f"{h.value}__{h.y}_vs_{h.x}{extra}.png".replace("/", "_")
        path = folder / name
        fig.savefig(path, dpi=110)
        written.append(path)
    return written
