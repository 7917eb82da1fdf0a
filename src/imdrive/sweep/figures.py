"""Heatmaps of a sweep's table: a metric over two axes, optionally in rows x cols panels.

A grid sweep aggregates the other axes (``mean``, ``min``, ``max`` or ``absmax``) into an image
per panel; a random sweep scatters its runs. Signed errors use a diverging colour map centred
on zero.

Cell annotations are sized to the cells (:func:`annotation_fontsize`; none when the cells are
too small to hold a readable number), written in black or white, whichever contrasts more with
the cell's colour (:func:`text_colour`), with two significant digits (:func:`cell_text`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imdrive._io import atomic_path
from imdrive.sweep.spec import Heatmap, Sweep

SIGNED_METRICS = ("speed_error_rpm", "speed_est_error_rpm", "R2_error_pct")

#: colour maps of a signed metric (diverging, centred on zero) and of any other metric
CMAP_SIGNED, CMAP_PLAIN = "RdBu_r", "viridis"

#: the colour of a cell with no finite value (PNGs and the HTML report): a mid grey, at least
#: 0.32 (RGB distance) from every colour of both maps. The light grey used before (0.85) was
#: within 0.11 of RdBu_r's near-white centre, so a signed metric's 0 read as "none finite".
NONE_FINITE = "#8c8c8c"


#: what the title says of :data:`NONE_FINITE`
NONE_FINITE_TEXT = "dark grey: none finite"


def plotly_scale(cmap: str, n: int = 21) -> list[list]:
    """The matplotlib colour map ``cmap`` as a plotly colour scale of ``n`` stops, so that the
    HTML report's cells have the PNGs' colours (plotly.js's own ``RdBu`` is grey at its
    centre, the colour of a cell with no value)."""
    import matplotlib

    colours = matplotlib.colormaps[cmap](np.linspace(0.0, 1.0, n))
    return [
        [float(t), "rgb({},{},{})".format(*(int(round(255 * c)) for c in rgba[:3]))]
        for t, rgba in zip(np.linspace(0.0, 1.0, n), colours, strict=True)
    ]


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
    from imdrive._figure import DisplayFigure as Figure

    rows = _levels(sweep, h.rows) if h.rows else [None]
    cols = _levels(sweep, h.cols) if h.cols else [None]
    # panels grow with their grid (up to a bound) so the cells can hold a readable number
    nx = 1 if sweep.random else len(_levels(sweep, h.x))
    ny = 1 if sweep.random else len(_levels(sweep, h.y))
    w = float(np.clip(0.5 * nx + 1.0, 3.6, 6.5))
    ht = float(np.clip(0.32 * ny + 1.0, 3.0, 5.0))
    fig = Figure(figsize=(w * len(cols) + 1.2, ht * len(rows) + 0.8), layout="constrained")
    axs = fig.subplots(len(rows), len(cols), squeeze=False)
    signed = h.value in SIGNED_METRICS
    vmin, vmax = colour_range(df[h.value], signed)
    style = {"cmap": CMAP_SIGNED if signed else CMAP_PLAIN, "vmin": vmin, "vmax": vmax}
    mappable = None
    annotate = []
    for r, rv in enumerate(rows):
        for c, cv in enumerate(cols):
            ax = axs[r, c]
            sel = df
            if h.rows:
                sel = sel[sel[h.rows] == rv]
            if h.cols:
                sel = sel[sel[h.cols] == cv]
            ax.set_facecolor(NONE_FINITE)
            if sweep.random:
                mappable = _scatter_panel(ax, sweep, sel, h, style)
            else:
                mappable, Z = _image_panel(ax, sweep, sel, h, style)
                annotate.append((ax, Z))
            ax.set_xlabel(h.x)
            ax.set_ylabel(h.y)
            title = ", ".join(
                f"{n} = {_fmt(v)}" for n, v in ((h.rows, rv), (h.cols, cv)) if n is not None
            )
            if title:
                ax.set_title(title, fontsize=9)
    if mappable is not None:
        fig.colorbar(mappable, ax=axs, label=h.value, shrink=0.9)
    agg = f" ({aggregation_text(sweep, h)}; {NONE_FINITE_TEXT})"
    fig.suptitle(f"{sweep.name}: {h.value}{agg}", fontsize=10)
    if annotate:
        fig.draw_without_rendering()  # the final layout gives the cells' size
        tiny = _tiny(np.concatenate([z.ravel() for _, z in annotate]))
        # one font size for the figure: the smallest cell and the longest number decide
        chars = max(
            (len(cell_text(v, tiny)) for _, Z in annotate for v in Z.ravel() if np.isfinite(v)),
            default=1,
        )
        sizes = [annotation_fontsize(*_cell_size_pt(ax, Z), chars) for ax, Z in annotate]
        if all(size is not None for size in sizes):
            for ax, Z in annotate:
                annotate_cells(ax, Z, mappable, tiny, min(sizes))
    return fig


def aggregation_text(sweep: Sweep, h: Heatmap) -> str:
    """What a cell of the heatmap is: one run, or ``h.agg`` over the axes not drawn (named).

    Parameters
    ----------
    sweep : Sweep
        The sweep.
    h : Heatmap
        The heatmap.

    Returns
    -------
    str
        ``"one dot per run"`` (a random sweep), ``"one run per cell"``, or e.g. ``"mean over
        load_Nm, R1_ratio (6 runs per cell)"``.
    """
    if sweep.random:
        return "one dot per run"
    drawn = {h.x, h.y, h.rows, h.cols}
    other = [a for a in sweep.axes if a.name not in drawn]
    if not other:
        return "one run per cell"
    n = int(np.prod([len(a.points()) for a in other]))
    if n == 1:
        return "one run per cell"
    names = ", ".join(a.name for a in other)
    return f"{h.agg} over {names} ({n} runs per cell)"


def axis_label(v) -> str:
    """An axis value as a tick label: 6 significant digits (``0.8``, not ``0.7999999999999999``)."""
    return f"{v:.6g}" if isinstance(v, float) else str(v)


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
    """A grid sweep's panel: the metric aggregated over the other axes, one cell per point;
    returns the image and its values (annotated once the layout is final)."""
    xs, ys, Z = heat_grid(sweep, sel, h)
    image = ax.imshow(
        np.ma.masked_invalid(Z), origin="lower", aspect="auto", interpolation="nearest", **style
    )
    ax.set_xticks(range(len(xs)), [_fmt(v) for v in xs], rotation=45)
    ax.set_yticks(range(len(ys)), [_fmt(v) for v in ys])
    return image, Z


#: smallest and largest annotation font, pt; below the smallest, cells are left blank
MIN_FONTSIZE = 5.0
MAX_FONTSIZE = 10.0


def _tiny(values) -> float:
    """Magnitudes below this print as 0: a thousandth of the 90th percentile of the finite
    magnitudes (not of the largest, so a few diverging runs do not zero out the rest)."""
    v = np.abs(np.asarray(values, dtype=float))
    v = v[np.isfinite(v)]
    return 1e-3 * float(np.percentile(v, 90)) if v.size else 0.0


def cell_text(v: float, tiny: float = 0.0) -> str:
    """A cell's number with two significant digits (integers from 10 up, ``19k`` from 10 000);
    ``"0"`` below ``tiny`` in magnitude (never ``-0.00``); ``""`` when not finite."""
    if not np.isfinite(v):
        return ""
    a = abs(v)
    if a < tiny or a == 0.0:
        return "0"
    if a >= 1e4:
        text = f"{v / 1e3:.0f}k"
    elif a >= 10:
        text = f"{v:.0f}"
    else:
        text = f"{v:.2g}"  # 7.4, 0.43, 0.061; 1e-07 only when every value is that small
    return text


def _luminance(rgba) -> float:
    """Relative luminance of an sRGB colour (WCAG 2)."""
    c = np.asarray(rgba[:3], dtype=float)
    lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return float(lin @ [0.2126, 0.7152, 0.0722])


def contrast_ratio(rgba1, rgba2) -> float:
    """WCAG contrast ratio of two colours, 1 (none) to 21 (black on white)."""
    l1, l2 = sorted((_luminance(rgba1), _luminance(rgba2)), reverse=True)
    return (l1 + 0.05) / (l2 + 0.05)


def text_colour(rgba) -> str:
    """``"black"`` or ``"white"``, whichever contrasts more with the cell colour ``rgba``
    (at least 4.5:1 for any colour, WCAG's threshold for small text)."""
    on_black = contrast_ratio(rgba, (0.0, 0.0, 0.0))
    on_white = contrast_ratio(rgba, (1.0, 1.0, 1.0))
    return "black" if on_black >= on_white else "white"


def annotation_fontsize(cell_w_pt: float, cell_h_pt: float, chars: int) -> float | None:
    """Font size, pt, that fits ``chars`` characters into a cell of the given size (points),
    at most :data:`MAX_FONTSIZE`; None when it would be below :data:`MIN_FONTSIZE`."""
    # a digit is about 0.6 em wide; keep a margin of half an em across and 45 % of the height
    size = min(0.45 * cell_h_pt, 0.9 * cell_w_pt / (0.6 * max(chars, 1) + 0.5), MAX_FONTSIZE)
    return size if size >= MIN_FONTSIZE else None


def _cell_size_pt(ax, Z) -> tuple[float, float]:
    """Width and height, pt, of one cell of the image of ``Z`` on ``ax`` (layout as drawn)."""
    box = ax.get_window_extent()
    pt = 72.0 / ax.figure.dpi
    ny, nx = Z.shape
    return box.width * pt / nx, box.height * pt / ny


def annotate_cells(ax, Z, mappable, tiny: float = 0.0, fontsize: float | None = None) -> list:
    """Write each finite value of ``Z`` into its cell of the image on ``ax``: font sized to the
    cell (``fontsize`` if given; nothing when too small), colour contrasting with the cell.
    Returns the texts."""
    texts = {(iy, ix): cell_text(v, tiny) for (iy, ix), v in np.ndenumerate(Z) if np.isfinite(v)}
    if not texts:
        return []
    size = fontsize or annotation_fontsize(
        *_cell_size_pt(ax, Z), max(len(t) for t in texts.values())
    )
    if size is None:
        return []
    out = []
    for (iy, ix), text in texts.items():
        colour = text_colour(mappable.cmap(mappable.norm(Z[iy, ix])))
        out.append(ax.text(ix, iy, text, ha="center", va="center", fontsize=size, color=colour))
    return out


def _fmt(v) -> str:
    return axis_label(v)


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
