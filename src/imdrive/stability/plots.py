"""Figures of the stability maps: heatmap and boundary overlays (``Figure`` objects, no pyplot:
they show in a notebook and leave the caller's matplotlib backend alone)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imdrive.stability.linear import STATUS_OK

#: the colour of a point without a steady state: the sweep heatmaps' "none finite" grey
#: (:data:`imdrive.sweep.figures.NONE_FINITE`), far from RdBu_r's near-white centre, which
#: is Re(s) = 0; the lighter 0.8 grey used before was close to it
NO_STEADY_STATE = "#8c8c8c"


def _grid(df, column):
    sp = np.unique(df["speed_rpm"].to_numpy())
    tq = np.unique(df["torque_Nm"].to_numpy())
    g = df.pivot_table(index="speed_rpm", columns="torque_Nm", values=column, dropna=False)
    return sp, tq, g.reindex(index=sp, columns=tq).to_numpy(dtype=float)


def map_figure(df, title: str = "", clip: float = 20.0):
    """Heatmap of the least stable mode's real part over speed x torque, boundary in black.

    Points without a usable steady state (current or voltage limit, none) are grey.

    Parameters
    ----------
    df : pandas.DataFrame
        A stability map (:func:`imdrive.stability.maps.stability_map`).
    title : str
        The figure's title (default: the count of unstable points).
    clip : float
        Colour range of the real part, 1/s (clipped to ±clip).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (shows itself in a notebook).
    """
    from imdrive._figure import new_figure

    d = df.copy()
    d["_re"] = np.where(d["status"] == STATUS_OK, d["max_real_1_per_s"], np.nan)
    d["_st"] = np.where(d["status"] == STATUS_OK, d["stable"].astype(float), np.nan)
    sp, tq, re = _grid(d, "_re")
    _, _, st = _grid(d, "_st")
    fig = new_figure(figsize=(7.5, 5.0), dpi=120, layout="constrained")
    ax = fig.add_subplot()
    ax.set_facecolor(NO_STEADY_STATE)
    mesh = ax.pcolormesh(
        tq, sp, np.clip(re, -clip, clip), cmap="RdBu_r", vmin=-clip, vmax=clip, shading="nearest"
    )
    cb = fig.colorbar(mesh, ax=ax)
    cb.set_label("largest Re(s) of the closed loop, 1/s (clipped)")
    if np.nanmin(st) < 0.5 < np.nanmax(st):
        ax.contour(tq, sp, np.nan_to_num(st, nan=1.0), levels=[0.5], colors="k", linewidths=1.5)
    ax.axvline(0.0, color="0.3", lw=0.6, ls=":")
    ax.set_xlabel("load torque, N m  (< 0: regenerating)")
    ax.set_ylabel("speed reference, rpm")
    n_un = int((d["status"] == STATUS_OK).sum() - d["stable"].sum())
    ax.set_title(
        title or f"small-signal stability: {n_un} unstable points, dark grey = no steady state"
    )
    return fig


def plot_map(df, path: Path, title: str = "", clip: float = 20.0) -> Path:
    """Write :func:`map_figure` as ``path`` (PNG; checked, atomic:
    :func:`imdrive._io.output_file`); returns the path."""
    with _output_file(path) as tmp:  # the path checked before the figure is drawn
        map_figure(df, title, clip).savefig(tmp, format="png")
    return Path(path)


def _output_file(path):
    from imdrive._io import output_file
    from imdrive.errors import ConfigError

    return output_file(path, lambda problem: ConfigError("path", problem))


def plot_overlay(frames: dict, path: Path, title: str = "") -> Path:
    """Write :func:`overlay_figure` as ``path`` (PNG; checked, atomic:
    :func:`imdrive._io.output_file`); returns the path."""
    with _output_file(path) as tmp:  # the path checked before the figure is drawn
        overlay_figure(frames, title).savefig(tmp, format="png")
    return Path(path)


def overlay_figure(frames: dict, title: str = ""):
    """Stable-region boundaries of several maps (label -> table) over speed x torque."""
    from matplotlib import colormaps
    from matplotlib.lines import Line2D

    from imdrive._figure import new_figure

    fig = new_figure(figsize=(7.5, 5.0), dpi=120, layout="constrained")
    ax = fig.add_subplot()
    colors = colormaps["viridis"](np.linspace(0.0, 0.9, max(len(frames), 1)))
    handles = []
    for (label, df), col in zip(frames.items(), colors, strict=False):
        d = df.copy()
        d["_st"] = np.where(d["status"] == STATUS_OK, d["stable"].astype(float), 0.0)
        sp, tq, st = _grid(d, "_st")
        if np.nanmin(st) < 0.5 < np.nanmax(st):
            ax.contourf(tq, sp, st, levels=[-0.5, 0.5], colors=[col], alpha=0.18)
            ax.contour(tq, sp, st, levels=[0.5], colors=[col], linewidths=1.8)
        handles.append(Line2D([], [], color=col, lw=2, label=label))
    ax.axvline(0.0, color="0.3", lw=0.6, ls=":")
    ax.set_xlabel("load torque, N m  (< 0: regenerating)")
    ax.set_ylabel("speed reference, rpm")
    ax.legend(handles=handles, title="unstable or no steady state (shaded)", fontsize=8)
    ax.set_title(title or "boundary of the stable region")
    return fig
