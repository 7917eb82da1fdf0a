"""A replay's figure (``replay.png``) and report (``report.html``): each estimator's speed
estimate against the recorded encoder, its error, its R2_hat.

The report is built on the run report's page (:func:`imdrive.run.report.html_page`: one
self-contained file, plotly.js inlined, linked zoomable panels), with the replay's summary as
tables. Both draw the thinned signals :func:`imdrive.run.replay.replay` kept (at most
:data:`~imdrive.run.replay.PLOT_POINTS` per signal), so a 10⁷-row replay draws as fast as a
short one.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np


def _panels(res) -> list[tuple[str, str, list[tuple[str, str]]]]:
    """(title, unit, [(column, label)]) of the panels that have data."""
    s = res.plot
    names = list(res.summary.get("estimators", {}))
    key = {n: n.replace("-", "_") for n in names}
    speed = [(f"speed_est_{key[n]}_rpm", n) for n in names]
    panels = []
    if "speed_enc_rpm" in s:
        panels.append(("speed", "rpm", [("speed_enc_rpm", "encoder"), *speed]))
        enc = np.asarray(s["speed_enc_rpm"])
        for col, n in speed:
            s[f"speed_err_{key[n]}_rpm"] = np.asarray(s[col]) - enc
        panels.append(
            ("speed estimate - encoder", "rpm", [(f"speed_err_{key[n]}_rpm", n) for n in names])
        )
    else:
        panels.append(("speed estimate (no encoder recorded)", "rpm", speed))
    panels.append(("R2_hat", "ohm", [(f"R2_hat_{key[n]}_ohm", n) for n in names]))
    return panels


def replay_figure(res):
    """The replay as a matplotlib figure: speed against the encoder, error, R2_hat."""
    from imdrive._figure import new_figure

    panels = _panels(res)
    fig = new_figure(figsize=(9, 2.4 * len(panels) + 0.6), layout="constrained")
    axes = fig.subplots(len(panels), 1, sharex=True, squeeze=False)[:, 0]
    t = np.asarray(res.plot["time_s"])
    for ax, (title, unit, cols) in zip(axes, panels, strict=True):
        for col, label in cols:
            style = {"color": "k", "lw": 1.0} if col == "speed_enc_rpm" else {"lw": 0.9}
            ax.plot(t, res.plot[col], label=label, **style)
        ax.set_ylabel(f"{title}\n({unit})", fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    axes[-1].set_xlabel("time (s)")
    fig.suptitle(f"replay of {Path(res.summary.get('recording', '')).name}", fontsize=10)
    return fig


def write_figure(res, path) -> Path:
    """Write :func:`replay_figure` as a PNG (checked, atomic: :func:`imdrive._io.output_file`)."""
    from imdrive._io import output_file
    from imdrive.errors import ConfigError

    with output_file(path, lambda problem: ConfigError("path", problem)) as tmp:
        replay_figure(res).savefig(tmp, dpi=110, format="png")
    return Path(path)


def report(res) -> str:
    """The replay's report as a self-contained HTML page."""
    from imdrive.run.plots import data_limits
    from imdrive.run.report import (
        TRACE_COLOURS,
        flatten,
        html_page,
        html_table,
        minmax_decimate,
    )

    panels = _panels(res)
    cols = {c: np.asarray(res.plot[c], dtype=float) for _, _, cs in panels for c, _ in cs}
    t, dec, b = minmax_decimate(np.asarray(res.plot["time_s"]), cols)
    arrays = {"t": t, **dec}
    n = len(panels)
    gap = 0.3 / n if n > 1 else 0.0
    h = (1.0 - gap * (n - 1)) / n
    layout: dict = {"hovermode": "x unified", "margin": {"l": 70, "r": 20, "t": 30, "b": 40}}
    layout["annotations"] = []
    data = []
    colour: dict[str, str] = {"encoder": "#000000"}
    for i, (title, unit, pcols) in enumerate(panels):
        ax = "" if i == 0 else str(i + 1)
        top = 1.0 - i * (h + gap)
        layout[f"xaxis{ax}"] = {"anchor": f"y{ax}", "title": {"text": "time (s)"}}
        if i:
            layout[f"xaxis{ax}"]["matches"] = "x"
        vals = np.concatenate([arrays[c] for c, _ in pcols])
        lims = data_limits(vals[np.isfinite(vals)]) if np.isfinite(vals).any() else (0.0, 1.0)
        layout[f"yaxis{ax}"] = {
            "domain": [top - h, top],
            "title": {"text": unit},
            "range": [float(x) for x in lims],
        }
        layout["annotations"].append(
            {"text": f"<b>{html.escape(title)}</b>", "xref": "paper", "yref": "paper", "x": 0,
             "y": top, "xanchor": "left", "yanchor": "bottom", "showarrow": False}
        )  # fmt: skip
        for col, label in pcols:
            colour.setdefault(label, TRACE_COLOURS[(len(colour) - 1) % len(TRACE_COLOURS)])
            data.append(
                {"type": "scatter", "mode": "lines", "name": label, "legendgroup": label,
                 "showlegend": i == 0 or "speed_enc_rpm" not in res.plot,
                 "x": {"$array": "t"}, "y": {"$array": col}, "xaxis": f"x{ax}",
                 "yaxis": f"y{ax}", "line": {"width": 1.2, "color": colour[label]},
                 "hovertemplate": f"%{{y:.5g}} {unit}"}
            )  # fmt: skip
    fig = {"div": "signals", "data": data, "layout": layout, "height": 260 * n + 80}
    s = res.summary
    notes = [
        html.escape(
            f"{s.get('rows_replayed')} control periods of {s.get('period_replayed_s'):g} s "
            f"replayed from {s.get('rows')} recorded rows (decimation {s.get('decimation')}) "
            f"on the scenario {s.get('scenario_name')}; model: {s.get('model')}."
        )
    ]
    for name, e in s.get("estimators", {}).items():
        err = e.get("speed_error_rpm")
        text = f"{name}: {e['status']}"
        if err:
            text += f", speed error RMS {err['rms']:.4g} rpm, largest {err['max']:.4g} rpm"
        cls = "" if e["status"] == "ok" else " class='bad'"
        notes.append(f"<span{cls}>{html.escape(text)}</span>")
    if b > 1:
        notes.append(html.escape(f"Shown as the min and max of every {b} kept samples."))
    keep = {k: v for k, v in s.items() if k != "scenario"}
    tables = [
        html_table(flatten(keep), "summary (summary.json)"),
        html_table(flatten(s.get("scenario", {})), "scenario replayed with"),
    ]
    title = f"imdrive replay: {s.get('scenario_name')}"
    return html_page(title, notes, [fig], arrays, tables)


def write_report(res, path) -> Path:
    """Write :func:`report` to ``path`` (UTF-8; :func:`~imdrive._io.output_file`)."""
    from imdrive._io import output_file
    from imdrive.errors import ConfigError

    with output_file(path, lambda problem: ConfigError("path", problem)) as tmp:
        tmp.write_text(report(res), encoding="utf-8")
    return Path(path)
