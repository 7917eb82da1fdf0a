"""The interactive HTML report of a run (``report.html``), and the page every report is built on.

One self-contained file that works offline: plotly.js is inlined (gzip-compressed and
base64-encoded, unpacked in the browser with ``DecompressionStream``: 1.9 MB instead of 4.8 MB),
the signals are inlined as base64 float32 arrays. Nothing is fetched from the network.

Functions
---------
minmax_decimate
    Shorten long signals for the browser without hiding their peaks (min and max per bucket).
run_report
    The report of a :class:`~imdrive.run.result.SimulationResult` as HTML text.
write_run_report
    Write it to a file.
html_page
    A report page: title, notes, plot panels (plotly.js figures), tables; shared with the sweep
    report (:mod:`imdrive.sweep.report`).

Notes
-----
The page records every script error (``window.onerror``, unhandled promise rejections,
``console.error``) into a hidden ``<pre id="report-errors">`` and sets ``data-status`` on
``<body>`` to ``rendered`` once every plot is drawn (``failed`` otherwise), so a headless
browser's ``--dump-dom`` shows whether the page worked (``tests/run/test_report.py``).
"""

from __future__ import annotations

import base64
import gzip
import html
import json
import math
from functools import cache
from pathlib import Path

import numpy as np

from imdrive.run.metrics import lost_control_rule

#: Points per trace in the browser at most (two per bucket: its min and its max)
MAX_POINTS = 8000

#: The plot panels of a run: (title, column unit, [(column, dash)]); a panel is drawn when at
#: least one of its columns exists. Each column is drawn in its display unit and labelled with
#: what it is (:func:`imdrive.run.plots.display_unit`, :data:`imdrive.run.plots.SIGNALS`:
#: flux in mWb, as in every figure of the package)
PANELS = [
    ("speed", "rpm", [("speed_rpm", "solid"), ("speed_ref_rpm", "dash"), ("speed_est_rpm", "dot")]),
    ("torque", "Nm", [("torque_Nm", "solid"), ("load_torque_Nm", "dash")]),
    ("phase currents", "A", [("i_a_A", "solid"), ("i_b_A", "solid"), ("i_c_A", "solid")]),
    (
        "synchronous-frame currents",
        "A",
        [("i_d_A", "solid"), ("id_ref_A", "dash"), ("i_q_A", "solid"), ("iq_ref_A", "dash")],
    ),
    (
        "MRAS flux error e_d0 and its synchronous detection",
        "Wb",
        [("e_d0_Wb", "solid"), ("e_d0_demod_Wb", "solid"), ("e_q0_Wb", "dot")],
    ),
    (
        "rotor resistance: estimate against the plant",
        "ohm",
        [("R2_ohm", "solid"), ("R2_hat_ohm", "dash")],
    ),
    ("terminal voltages", "V", [("v_alpha_V", "solid"), ("v_beta_V", "solid")]),
    ("rotor flux", "Wb", [("flux_Wb", "solid")]),
]


def minmax_decimate(
    t: np.ndarray, columns: dict[str, np.ndarray], max_points: int = MAX_POINTS
) -> tuple[np.ndarray, dict[str, np.ndarray], int]:
    """Shorten signals on a shared time axis for plotting, keeping every peak.

    The samples are cut into buckets of ``b`` consecutive samples; each bucket gives two points,
    at its first and its last time, holding its minimum and its maximum in the order they
    occur. The envelope of the signal is kept exactly (no peak is hidden); a peak's time moves by
    less than one bucket.

    Parameters
    ----------
    t : numpy.ndarray
        The shared time axis, s.
    columns : dict of str to numpy.ndarray
        Signals of ``len(t)`` samples.
    max_points : int
        Points per signal at most; shorter signals are returned as they are.

    Returns
    -------
    t_out : numpy.ndarray
        The time axis of the decimated signals.
    out : dict of str to numpy.ndarray
        The decimated signals.
    b : int
        Samples per bucket (1: not decimated).
    """
    n = len(t)
    if n <= max_points:
        return t, dict(columns), 1
    b = math.ceil(n / (max_points // 2))
    m = math.ceil(n / b)
    pad = m * b - n
    first = np.arange(m) * b
    last = np.minimum(first + b - 1, n - 1)
    t_out = np.empty(2 * m)
    t_out[0::2] = t[first]
    t_out[1::2] = t[last]
    out = {}
    rows = np.arange(m)
    for name, y in columns.items():
        y2 = np.pad(np.asarray(y, dtype=float), (0, pad), mode="edge").reshape(m, b)
        imin = np.argmin(y2, axis=1)  # a NaN is its bucket's min and max: the gap stays
        imax = np.argmax(y2, axis=1)
        lo, hi = y2[rows, imin], y2[rows, imax]
        min_first = imin <= imax
        v = np.empty(2 * m)
        v[0::2] = np.where(min_first, lo, hi)
        v[1::2] = np.where(min_first, hi, lo)
        out[name] = v
    return t_out, out, b


def _b64_f32(a: np.ndarray) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype="<f4").tobytes()).decode("ascii")


@cache
def _plotly_js_gz_b64() -> str:
    """plotly.js, gzip-compressed and base64-encoded.

    Compressing its 4.8 MB takes 0.3 s, a tenth of a warm ``imdrive run``: it is done once per
    plotly version and kept in the cache folder (``plotly-<version>.b64``, beside the
    kernels'), and once per process where that folder cannot be written.
    """
    import contextlib
    import os

    import plotly

    from imdrive._cache import cache_root

    kept = None
    with contextlib.suppress(OSError):
        kept = cache_root() / f"plotly-{plotly.__version__}.b64"
        text = kept.read_text("ascii")
        if text:
            return text
    from plotly.offline import get_plotlyjs

    raw = get_plotlyjs().encode("utf-8")
    text = base64.b64encode(gzip.compress(raw, compresslevel=6, mtime=0)).decode("ascii")
    if kept is not None:
        with contextlib.suppress(OSError):  # written whole, then renamed: never half a file
            tmp = kept.with_name(f"{kept.name}.{os.getpid()}.tmp")
            tmp.write_text(text, "ascii")
            os.replace(tmp, kept)
    return text


def _json_for_script(obj) -> str:
    """JSON safe inside a ``<script>`` element (no ``</``)."""
    return json.dumps(obj, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")


def _finite(obj):
    """``obj`` with non-finite floats as None (JSON has no NaN)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    return obj


def flatten(d: dict, prefix: str = "") -> list[tuple[str, object]]:
    """``{"a": {"b": 1}}`` -> ``[("a.b", 1)]`` (lists kept as values)."""
    rows = []
    for k, v in d.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            rows.extend(flatten(v, key + "."))
        else:
            rows.append((key, v))
    return rows


def _fmt(v) -> str:
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, list | tuple):
        return json.dumps(_finite(list(v)))
    return str(v)


def html_table(rows: list[tuple[str, object]], caption: str, header=("key", "value")) -> str:
    """A two-column HTML table (escaped)."""
    body = "".join(
        f"<tr><td>{html.escape(str(k))}</td><td>{html.escape(_fmt(v))}</td></tr>" for k, v in rows
    )
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    return (
        f"<details open><summary>{html.escape(caption)}</summary>"
        f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table></details>"
    )


_STYLE = """
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:1.5em;color:#222}
h1{font-size:1.4em;margin-bottom:.2em} .note{color:#555;font-size:.9em;margin:.3em 0}
.bad{color:#b00;font-weight:bold} .plot{width:100%;min-height:300px}
details{margin:1em 0} summary{font-weight:bold;cursor:pointer;font-size:1.1em}
table{border-collapse:collapse;font-size:.85em;margin-top:.4em}
td,th{border:1px solid #ccc;padding:2px 8px;text-align:left} td:nth-child(2){font-family:monospace}
#report-loading{color:#555}
"""

# Errors of the page (script errors, rejected promises, console.error) go into the DOM, where a
# headless browser's --dump-dom shows them.
_ERRORS_JS = """
(function () {
  function rec(m) {
    var e = document.getElementById('report-errors');
    if (e) { e.hidden = false; e.textContent += String(m) + '\\n'; }
    else { (window.__early = window.__early || []).push(String(m)); }
  }
  window.__recordError = rec;
  window.addEventListener('error', function (e) { rec('error: ' + e.message); });
  window.addEventListener('unhandledrejection', function (e) {
    rec('unhandled rejection: ' + ((e.reason && e.reason.stack) || e.reason));
  });
  var ce = console.error;
  console.error = function () {
    rec('console.error: ' + Array.prototype.join.call(arguments, ' '));
    return ce.apply(console, arguments);
  };
})();
"""

# Unpack plotly.js, decode the data, draw every figure; set body[data-status].
_MAIN_JS = """
(async function () {
  var body = document.body;
  (window.__early || []).forEach(window.__recordError);
  try {
    if (typeof DecompressionStream === 'undefined') {
      throw new Error('this browser has no DecompressionStream: open the report in a ' +
                      'browser from 2023 or later');
    }
    function bytes(b64) {
      var s = atob(b64), a = new Uint8Array(s.length);
      for (var i = 0; i < s.length; i++) a[i] = s.charCodeAt(i);
      return a;
    }
    var gz = bytes(document.getElementById('plotly-gz').textContent.trim());
    var unpacked = new Blob([gz]).stream().pipeThrough(new DecompressionStream('gzip'));
    var js = await new Response(unpacked).text();
    var s = document.createElement('script');
    s.textContent = js;
    document.head.appendChild(s);
    var data = JSON.parse(document.getElementById('report-data').textContent);
    var arrays = {};
    for (var k in data.arrays) arrays[k] = new Float32Array(bytes(data.arrays[k]).buffer);
    function resolve(o) {
      if (Array.isArray(o)) return o.map(resolve);
      if (o && typeof o === 'object') {
        if (o.$array !== undefined) return arrays[o.$array];
        var r = {};
        for (var key in o) r[key] = resolve(o[key]);
        return r;
      }
      return o;
    }
    document.getElementById('report-loading').remove();
    for (var i = 0; i < data.figures.length; i++) {
      var f = resolve(data.figures[i]);
      await Plotly.newPlot(f.div, f.data, f.layout, {responsive: true, displaylogo: false});
    }
    body.dataset.status = document.getElementById('report-errors').hidden ? 'rendered' : 'failed';
  } catch (e) {
    window.__recordError('error: ' + ((e && e.stack) || e));
    body.dataset.status = 'failed';
    var l = document.getElementById('report-loading');
    if (l) l.textContent = 'The plots could not be drawn: ' + e;
  }
})();
"""


def html_page(
    title: str,
    notes: list[str],
    figures: list[dict],
    arrays: dict[str, np.ndarray],
    tables: list[str],
) -> str:
    """A self-contained report page.

    Parameters
    ----------
    title : str
        The page's heading.
    notes : list of str
        HTML paragraphs under the heading (already escaped).
    figures : list of dict
        plotly.js figures ``{"div": id, "data": [...], "layout": {...}}``; ``{"$array": name}``
        anywhere in them stands for the float32 array ``arrays[name]``.
    arrays : dict of str to numpy.ndarray
        The arrays the figures refer to (inlined as base64 float32).
    tables : list of str
        HTML blocks after the plots (:func:`html_table`).

    Returns
    -------
    str
    """
    divs = "".join(
        f'<div id="{html.escape(f["div"])}" class="plot" style="height:{f.get("height", 400)}px">'
        "</div>"
        for f in figures
    )
    data = {
        "figures": _finite(figures),
        "arrays": {k: _b64_f32(v) for k, v in arrays.items()},
    }
    return (
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>"
        f"<title>{html.escape(title)}</title><style>{_STYLE}</style>"
        f"<script>{_ERRORS_JS}</script></head>\n"
        f'<body data-status="loading"><h1>{html.escape(title)}</h1>'
        + "".join(f"<p class='note'>{n}</p>" for n in notes)
        + '<p id="report-loading">Drawing the plots...</p>'
        + divs
        + "".join(tables)
        + '<pre id="report-errors" hidden></pre>\n'
        + f'<script id="plotly-gz" type="application/octet-stream">{_plotly_js_gz_b64()}'
        "</script>\n"
        + f'<script id="report-data" type="application/json">{_json_for_script(data)}</script>\n'
        + f"<script>{_MAIN_JS}</script></body></html>\n"
    )


#: trace colours (plotly's default sequence), assigned per signal in order of appearance
TRACE_COLOURS = (
    "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
    "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf",
)  # fmt: skip

ZOOM_TITLE = "flux error, steady-state zoom (y-range from the samples after {t0:g} s)"


def _run_figure(res, max_points: int) -> tuple[dict, dict, int]:
    """The stacked time plots of a run: each panel with its own time axis, all linked (zooming
    one zooms all); after the flux-error panel, the same errors with the y-range of the
    steady state (:func:`imdrive.run.plots.steady_start`), where the start-up transient would
    hide them (as ``estimator.png``)."""
    from imdrive.run.plots import (
        data_limits,
        display_unit,
        signal_label,
        steady_start,
        zoom_limits,
    )

    s = res.signals
    panels = []
    for title, _, cols in PANELS:
        present = [(c, signal_label(c, res), d) for c, d in cols if c in s]
        if not present:
            continue
        panels.append((title, display_unit(cols[0][0])[0], present, None))
        if cols[0][0] == "e_d0_Wb":
            t0 = steady_start(res)
            win = np.asarray(s["time_s"]) >= t0
            vals = np.concatenate(
                [np.asarray(s[c])[win] * display_unit(c)[1] for c, _, _ in present]
            )
            if vals.size:
                panels.append((ZOOM_TITLE.format(t0=t0), panels[-1][1], present, zoom_limits(vals)))
    t_dec, dec, b = minmax_decimate(
        s["time_s"],
        {c[0]: np.asarray(s[c[0]]) * display_unit(c[0])[1] for p in panels for c in p[2]},
        max_points,
    )
    arrays = {"t": t_dec, **dec}
    n = len(panels)
    gap = 0.3 / n if n > 1 else 0.0  # room for each panel's time axis
    h = (1.0 - gap * (n - 1)) / n
    layout: dict = {
        "hovermode": "x unified",
        "margin": {"l": 70, "r": 20, "t": 30, "b": 40},
        "legend": {"orientation": "v"},
        "annotations": [],
        "showlegend": True,
    }
    data = []
    colour: dict[str, str] = {}  # one colour per signal, the same in the zoom panel
    for i, (title, unit, cols, y_range) in enumerate(panels):
        ax = "" if i == 0 else str(i + 1)
        top = 1.0 - i * (h + gap)
        layout[f"xaxis{ax}"] = {
            "anchor": f"y{ax}",
            "showticklabels": True,
            "title": {"text": "time (s)", "standoff": 2},
            **({"matches": "x"} if i else {}),
        }
        yaxis = {"domain": [top - h, top], "title": {"text": unit}}
        zoom = y_range is not None
        # every panel's range from its data: plotly.js spans a constant v as v - 1 .. v + 1
        if y_range is None:
            y_range = data_limits(np.concatenate([arrays[c] for c, _, _ in cols]))
        yaxis["range"] = [float(x) for x in y_range]
        layout[f"yaxis{ax}"] = yaxis
        layout["annotations"].append(
            {
                "text": f"<b>{html.escape(title)}</b>",
                "xref": "paper",
                "yref": "paper",
                "x": 0,
                "y": top,
                "xanchor": "left",
                "yanchor": "bottom",
                "showarrow": False,
            }
        )
        for col, label, dash in cols:
            colour.setdefault(col, TRACE_COLOURS[len(colour) % len(TRACE_COLOURS)])
            data.append(
                {
                    "type": "scatter",
                    "mode": "lines",
                    "name": label,
                    "legendgroup": title,
                    "legendgrouptitle": {"text": title} if col == cols[0][0] else None,
                    "showlegend": not zoom,
                    "x": {"$array": "t"},
                    "y": {"$array": col},
                    "xaxis": f"x{ax}",
                    "yaxis": f"y{ax}",
                    "line": {"dash": dash, "width": 1.2, "color": colour[col]},
                    "hovertemplate": f"%{{y:.5g}} {unit}",
                }
            )
    for d in data:
        if d["legendgrouptitle"] is None:
            del d["legendgrouptitle"]
    fig = {"div": "signals", "data": data, "layout": layout, "height": 260 * n + 80}
    return fig, arrays, b


def _summary_rows(summary: dict) -> list[tuple[str, object]]:
    keep = {k: v for k, v in summary.items() if k not in ("scenario", "versions")}
    return flatten(keep)


def run_report(res, max_points: int = MAX_POINTS, folder=None) -> str:
    """The interactive report of a run, as HTML text.

    Parameters
    ----------
    res : SimulationResult
        The run.
    max_points : int
        Points per trace at most (:func:`minmax_decimate`).
    folder : str or os.PathLike, optional
        Where the page is written: the scenario's file paths are shown relative to it
        (:func:`~imdrive.config.summary_file.portable_summary`), never absolute.

    Returns
    -------
    str
        A self-contained HTML page: linked zoomable time plots (speed, torque, currents, e_d0
        and its demodulation, R̂2 against R2, voltages, flux), the summary and the scenario as
        tables.
    """
    from imdrive.config.summary_file import portable_summary

    sc = res.scenario
    summary = res.summary()
    if folder is not None:
        summary = portable_summary(summary, folder)
    fig, arrays, b = _run_figure(res, max_points)
    notes = [html.escape(sc.description)] if sc.description else []
    st = f"simulated {res.end_time_s:g} s in {res.wall_time_s:.3g} s wall"
    if res.diverged:
        notes.append(f"<span class='bad'>{html.escape(res.divergence_message)}</span>")
    elif res.lost_control:
        notes.append(f"<span class='bad'>{html.escape(res.lost_control_message)}</span>")
    else:
        notes.append(html.escape(f"{lost_control_rule(sc)}: none"))
    v = summary["verdict"]  # the run's status (imdrive.run.status): ok, or every cause
    cls = "" if v["verdict_ok"] else " class='bad'"
    notes.append(f"<span{cls}>status: {html.escape(v['verdict_text'])}</span>")
    notes.append(html.escape(st))
    n = len(res.time_s)
    if b > 1:
        notes.append(
            html.escape(
                f"{n} logged samples shown as the min and max of every {b} ({len(arrays['t'])} "
                "points per trace): every peak is kept, a peak's time may move by up to "
                f"{b} samples. Drag to zoom (linked time axes), double-click to reset."
            )
        )
    else:
        notes.append("Drag to zoom (linked time axes), double-click to reset.")
    tables = [
        html_table(_summary_rows(summary), "summary (summary.json)"),
        html_table(flatten(summary["scenario"]), "scenario as run"),
        html_table(list(summary["versions"].items()), "versions"),
    ]
    return html_page(f"imdrive: {sc.name}", notes, [fig], arrays, tables)


def write_run_report(res, path, max_points: int = MAX_POINTS) -> Path:
    """Write :func:`run_report` to ``path`` (UTF-8; checked and replaced atomically,
    :func:`imdrive._io.output_file`); return the path."""
    import os

    from imdrive._io import output_file
    from imdrive.errors import ConfigError

    def refuse(problem):
        return ConfigError("path", problem)

    if not isinstance(path, str | os.PathLike):
        raise refuse(f"must be a file path, got {type(path).__name__}")
    path = Path(path)
    with output_file(path, refuse) as tmp:
        tmp.write_text(run_report(res, max_points, path.parent), encoding="utf-8")
    return path
