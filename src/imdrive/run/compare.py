"""Several runs side by side: their signals overlaid, their metrics in one table, one report.

:func:`compare` takes result folders (what ``imdrive run`` and :meth:`SimulationResult.save
<imdrive.run.result.SimulationResult.save>` write) or results in memory; ``imdrive compare
RUN_DIR... --out DIR`` writes what :meth:`Comparison.save` writes: ``compare.png`` (one panel
per signal, a line per run), ``metrics.csv`` (a column per run) and ``report.html`` (the same
signals in linked zoomable panels, each with its own time axis, and the metrics table).
"""

from __future__ import annotations

import html
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from imdrive.config.summary_file import read_summary_json
from imdrive.config.user_files import lexists, user_file_problem, user_folder_problem
from imdrive.errors import ConfigError

#: the default panels: (quantity, columns); a panel is drawn when a run has one of its columns
DEFAULT_PANELS = (
    ("speed", ("speed_rpm",)),
    ("speed estimate error", ("speed_est_error_rpm",)),
    ("torque", ("torque_Nm",)),
    ("stator current magnitude", ("i_s_mag_A",)),
    ("MRAS flux error e_d0", ("e_d0_Wb",)),
    ("rotor resistance estimate", ("R2_hat_ohm", "R2_est_ohm")),
)


@dataclass
class Run:
    """One run of a comparison: its label, signals (SI columns, as ``res.signals``), scenario,
    ``summary.json`` and metrics (:func:`imdrive.run.metrics.drive_metrics`)."""

    label: str
    signals: dict
    scenario: object
    summary: dict
    metrics: dict = field(default_factory=dict)


def _derived_columns(s: dict) -> dict:
    s = dict(s)
    if "i_alpha_A" in s and "i_beta_A" in s:
        s["i_s_mag_A"] = np.hypot(s["i_alpha_A"], s["i_beta_A"])
    if "speed_est_rpm" in s and "speed_rpm" in s:
        s["speed_est_error_rpm"] = np.asarray(s["speed_est_rpm"]) - np.asarray(s["speed_rpm"])
    return s


def _metrics(signals, scenario, summary) -> dict:
    from imdrive.run.metrics import drive_metrics

    stub = SimpleNamespace(
        signals=signals,
        scenario=scenario,
        status=summary.get("status", 0),
        diverged=bool(summary.get("diverged")),
        k_end=int(summary.get("control_periods", 0)),
    )
    m = drive_metrics(stub)
    m["real_time_factor"] = summary.get("real_time_factor")
    return m


def load_run(folder, label: str | None = None) -> Run:
    """A result folder as a :class:`Run` (its ``timeseries.csv`` or ``timeseries.parquet``
    and ``summary.json``).

    Parameters
    ----------
    folder : str or pathlib.Path
        A folder written by ``imdrive run`` or ``SimulationResult.save``.
    label : str, optional
        Its name in the comparison (default: the folder's name).

    Returns
    -------
    Run

    Raises
    ------
    ConfigError
        The folder is not a result with its time series.
    """
    import pandas as pd

    from imdrive.config.scenario import Scenario

    if not isinstance(folder, str | os.PathLike):
        raise ConfigError("run", f"must be a result folder's path, got {type(folder).__name__}")
    problem = user_folder_problem(folder)
    if problem is not None:
        raise ConfigError("run", problem)
    folder = Path(folder)
    summary_path = folder / "summary.json"
    if not lexists(summary_path):
        raise ConfigError("run", f"{folder}: no summary.json (not a result folder)")
    summary = read_summary_json(summary_path, "run")
    if is_replay_summary(summary):
        runs = load_replay(folder, label, summary)
        if len(runs) != 1:
            raise ConfigError(
                "run",
                f"{folder}: a replay of {len(runs)} estimators (compare() takes it, one line "
                "per estimator)",
            )
        return runs[0]
    table = None
    for name, reader in (("timeseries.parquet", pd.read_parquet), ("timeseries.csv", pd.read_csv)):
        path = folder / name
        if not lexists(path):
            continue
        problem = user_file_problem(path, "table")
        if problem is not None:
            raise ConfigError("run", problem)
        _check_size(path)
        try:
            table = reader(path)
        except (MemoryError, KeyboardInterrupt):
            raise
        except Exception as exc:  # pandas' and pyarrow's many errors: not a table
            why = _one_line(exc)
            raise ConfigError("run", f"{path}: cannot be read as a table ({why})") from None
        break
    if table is None:
        raise ConfigError(
            "run", f"{folder}: no timeseries.csv or .parquet (run it with output.csv = true)"
        )
    signals = _signals(table, path)
    scenario = Scenario.read(str(summary_path))
    return Run(
        label or folder.name, signals, scenario, summary, _metrics(signals, scenario, summary)
    )


def is_replay_summary(summary: dict) -> bool:
    """Whether a ``summary.json`` is a replay's (:mod:`imdrive.run.replay`)."""
    return "estimators" in summary and "period_replayed_s" in summary


def load_replay(folder, label: str | None = None, summary: dict | None = None) -> list[Run]:
    """A replay folder as one :class:`Run` per estimator: ``speed_rpm`` the recorded encoder,
    ``speed_est_rpm`` and ``R2_hat_ohm`` the estimator's, labelled ``FOLDER: ESTIMATOR``;
    its metrics the replay's (speed error against the encoder, R2_hat at the end, status).

    Raises
    ------
    ConfigError
        The folder has no readable ``timeseries.parquet``.
    """
    import pandas as pd

    folder = Path(folder)
    if summary is None:
        summary = read_summary_json(folder / "summary.json", "run")
    path = folder / "timeseries.parquet"
    if not lexists(path):
        raise ConfigError("run", f"{folder}: a replay without its timeseries.parquet")
    problem = user_file_problem(path, "table")
    if problem is not None:
        raise ConfigError("run", problem)
    _check_size(path)
    try:
        table = pd.read_parquet(path)
    except (MemoryError, KeyboardInterrupt):
        raise
    except Exception as exc:  # pyarrow's many errors: not a table
        raise ConfigError("run", f"{path}: cannot be read as a table ({_one_line(exc)})") from None
    s = _signals(table, path)
    base = label or folder.name
    name = summary.get("scenario_name")
    scenario = SimpleNamespace(
        name=str(name), description=f"replay of {summary.get('recording')} on {name}"
    )
    runs = []
    for name, e in summary["estimators"].items():
        key = name.replace("-", "_")
        sig = {"time_s": s["time_s"]}
        if "speed_enc_rpm" in s:
            sig["speed_rpm"] = s["speed_enc_rpm"]
        for col, src in (("speed_est_rpm", "speed_est"), ("R2_hat_ohm", "R2_hat")):
            unit = col.rsplit("_", 1)[1]
            if f"{src}_{key}_{unit}" in s:
                sig[col] = s[f"{src}_{key}_{unit}"]
        err = e.get("speed_error_rpm") or {}
        m = {
            "status": e.get("status"),
            "speed_error_mean_rpm": err.get("mean"),
            "speed_error_rms_rpm": err.get("rms"),
            "speed_error_max_rpm": err.get("max"),
            "R2_hat_end_ohm": e.get("R2_hat_end_ohm"),
            "real_time_factor": summary.get("real_time_factor"),
        }
        runs.append(Run(f"{base}: {name}", sig, scenario, summary, m))
    return runs


#: the largest result file :func:`load_run` reads (a bound, not a format rule: a 3 s run at
#: the default logging is a few MB; a week-long one in Parquet stays below it)
MAX_RESULT_BYTES = 4 * 1024**3


def _one_line(exc: BaseException) -> str:
    text = str(exc).splitlines()[0][:200] if str(exc) else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _check_size(path: Path, limit: int = MAX_RESULT_BYTES) -> None:
    size = path.stat().st_size
    if size > limit:
        raise ConfigError("run", f"{path}: {size} bytes, more than a result holds ({limit})")


def _signals(table, path: Path) -> dict:
    """The table's columns as float arrays: a time series with ``time_s`` and rows, every
    column numeric (one line naming the file and the column otherwise)."""
    if "time_s" not in table.columns:
        raise ConfigError("run", f"{path}: no time_s column (not an imdrive time series)")
    if len(table) == 0:
        raise ConfigError("run", f"{path}: no rows (an empty time series)")
    signals = {}
    for c in table.columns:
        try:
            signals[str(c)] = table[c].to_numpy(dtype=float)
        except (TypeError, ValueError):
            raise ConfigError("run", f"{path}: column {str(c)[:60]!r} is not numeric") from None
    return signals


def _from_result(res, label: str | None) -> Run:
    summary = res.summary()
    m = res.metrics()
    m["real_time_factor"] = summary.get("real_time_factor")
    return Run(label or res.scenario.name, dict(res.signals), res.scenario, summary, m)


@dataclass
class Comparison:
    """Runs side by side (:func:`compare`)."""

    runs: list[Run]
    panels: list[tuple[str, tuple[str, ...]]]

    @property
    def metrics(self):
        """The metrics side by side: a row per metric, a column per run (pandas.DataFrame)."""
        import pandas as pd

        return pd.DataFrame({r.label: pd.Series(r.metrics) for r in self.runs})

    def figure(self):
        """The overlaid signals: a panel per quantity, a line per run, each panel with its time
        axis (matplotlib Figure; shows itself in a notebook)."""
        from imdrive._figure import new_figure
        from imdrive.run.plots import display_unit

        fig = new_figure(figsize=(8.5, 2.3 * len(self.panels) + 0.8), layout="constrained")
        axes = fig.subplots(len(self.panels), 1, sharex=True, squeeze=False)[:, 0]
        for ax, (quantity, cols) in zip(axes, self.panels, strict=True):
            unit = ""
            for j, run in enumerate(self.runs):
                s = _derived_columns(run.signals)
                for col in cols:
                    if col not in s:
                        continue
                    unit, k = display_unit(col)
                    style = "-" if len(cols) == 1 else ["-", "--", ":"][cols.index(col) % 3]
                    ax.plot(s["time_s"], np.asarray(s[col]) * k, style, lw=0.9,
                            color=f"C{j}", label=run.label if col == cols[0] else None)  # fmt: skip
            ax.set_ylabel(f"{quantity} ({unit})" if unit else quantity, fontsize=8)
            ax.grid(alpha=0.3)
            ax.tick_params(labelbottom=True)
            ax.set_xlabel("time (s)", fontsize=8)
        axes[0].legend(fontsize=8, loc="best")
        fig.suptitle("imdrive compare: " + ", ".join(r.label for r in self.runs))
        return fig

    def _repr_png_(self):
        return self.figure()._repr_png_()

    def report(self) -> str:
        """The comparison as a self-contained HTML page (:func:`imdrive.run.report.html_page`)."""
        from imdrive.run.plots import display_unit
        from imdrive.run.report import MAX_POINTS, html_page, minmax_decimate

        figures, arrays, data = [], {}, []
        n = len(self.panels)
        gap, h_px = 0.06, 240
        dom = (1.0 - gap * (n - 1)) / n
        layout: dict = {
            "hovermode": "x unified",
            "margin": {"l": 70, "r": 20, "t": 30, "b": 40},
            "annotations": [],
        }
        for i, (quantity, cols) in enumerate(self.panels):
            ax = "" if i == 0 else str(i + 1)
            top = 1.0 - i * (dom + gap)
            unit = ""
            for j, run in enumerate(self.runs):
                s = _derived_columns(run.signals)
                present = [c for c in cols if c in s]
                if not present:
                    continue
                unit = display_unit(present[0])[0]
                t, dec, _ = minmax_decimate(
                    s["time_s"], {c: np.asarray(s[c]) * display_unit(c)[1] for c in present},
                    MAX_POINTS,
                )  # fmt: skip
                arrays[f"t{i}_{j}"] = t
                for c in present:
                    arrays[f"y{i}_{j}_{c}"] = dec[c]
                    data.append({
                        "type": "scatter", "mode": "lines",
                        "name": run.label + ("" if len(present) == 1 else f" {c}"),
                        "legendgroup": run.label, "showlegend": i == 0,
                        "x": {"$array": f"t{i}_{j}"}, "y": {"$array": f"y{i}_{j}_{c}"},
                        "xaxis": f"x{ax}", "yaxis": f"y{ax}",
                        "line": {"color": _COLOURS[j % len(_COLOURS)], "width": 1.2},
                        "hovertemplate": f"%{{y:.5g}} {unit}",
                    })  # fmt: skip
            layout[f"xaxis{ax}"] = {
                "anchor": f"y{ax}",
                "domain": [0.0, 1.0],
                "title": {"text": "time (s)"},
                "showticklabels": True,
                **({"matches": "x"} if i else {}),
            }
            layout[f"yaxis{ax}"] = {"domain": [top - dom, top], "title": {"text": unit}}
            layout["annotations"].append({
                "text": f"<b>{html.escape(quantity)}</b>", "xref": "paper", "yref": "paper",
                "x": 0, "y": top, "xanchor": "left", "yanchor": "bottom", "showarrow": False,
            })  # fmt: skip
        figures.append({"div": "signals", "data": data, "layout": layout, "height": h_px * n + 80})
        notes = [
            html.escape(f"{r.label}: {r.scenario.description or r.scenario.name}")
            for r in self.runs
        ] + ["Drag to zoom (linked time axes), double-click to reset."]
        return html_page("imdrive compare", notes, figures, arrays, [self._metrics_html()])

    def _metrics_html(self) -> str:
        df = self.metrics
        head = "".join(f"<th>{html.escape(str(c))}</th>" for c in ["metric", *df.columns])
        rows = []
        for name, row in df.iterrows():
            cells = "".join(f"<td>{html.escape(_cell(v))}</td>" for v in row)
            rows.append(f"<tr><td>{html.escape(str(name))}</td>{cells}</tr>")
        return (
            "<details open><summary>metrics side by side</summary><table><thead><tr>"
            f"{head}</tr></thead><tbody>{''.join(rows)}</tbody></table></details>"
        )

    def save(self, out_dir) -> list[Path]:
        """Write ``compare.png``, ``metrics.csv`` and ``report.html`` into ``out_dir``.

        Parameters
        ----------
        out_dir : str or pathlib.Path
            The folder (created).

        Returns
        -------
        list of pathlib.Path
            The files written.
        """
        from imdrive._io import atomic_path

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "compare.png", out / "metrics.csv", out / "report.html"]
        with atomic_path(paths[0]) as tmp:
            self.figure().savefig(tmp, dpi=110, format="png")
        with atomic_path(paths[1]) as tmp:
            self.metrics.to_csv(tmp, index_label="metric")
        with atomic_path(paths[2]) as tmp:
            Path(tmp).write_text(self.report(), encoding="utf-8")
        return paths


_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2")


def _cell(v) -> str:
    if v is None:
        return "—"
    if isinstance(v, bool | np.bool_):
        return "true" if v else "false"
    if isinstance(v, float | np.floating):
        return "—" if math.isnan(v) else f"{v:.4g}"
    return str(v)


def _replay_folder(folder) -> bool:
    if not isinstance(folder, str | os.PathLike):
        return False
    p = Path(folder) / "summary.json"
    if user_file_problem(p) is not None:
        return False
    try:
        return is_replay_summary(read_summary_json(p, "run"))
    except ConfigError:
        return False


def compare(runs, labels=None, signals=None) -> Comparison:
    """Several runs side by side.

    Parameters
    ----------
    runs : iterable of (str, pathlib.Path or SimulationResult)
        Result folders, replay folders (``imdrive replay``: one line per estimator,
        :func:`load_replay`) or results in memory (at least one).
    labels : list of str, optional
        Their names (default: a folder's name, a result's scenario name).
    signals : list of str, optional
        Columns to overlay, one panel each (default: speed, speed-estimate error, torque,
        stator current magnitude, e_d0, R̂2, those some run has).

    Returns
    -------
    Comparison
        ``.metrics`` (a table), ``.figure()``, ``.report()`` (HTML), ``.save(out_dir)``.

    Raises
    ------
    ConfigError
        No run, a folder that is not a result, a signal no run has.
    """
    from imdrive.run.result import SimulationResult

    if isinstance(runs, str | os.PathLike | SimulationResult) or not hasattr(runs, "__iter__"):
        raise ConfigError(
            "runs", f"must be a list of result folders or results, got {type(runs).__name__}"
        )
    runs = list(runs)
    if not runs:
        raise ConfigError("runs", "give at least one run")
    if labels is not None and (isinstance(labels, str) or not hasattr(labels, "__iter__")):
        raise ConfigError("labels", f"must be a list of names, got {type(labels).__name__}")
    labels = list(labels) if labels is not None else [None] * len(runs)
    if len(labels) != len(runs):
        raise ConfigError("labels", f"{len(labels)} names for {len(runs)} runs: give one each")
    loaded = []
    for r, lab in zip(runs, labels, strict=True):
        if isinstance(r, SimulationResult):
            loaded.append(_from_result(r, lab))
        elif _replay_folder(r):  # a replay: a line per estimator
            loaded.extend(load_replay(r, lab))
        else:
            loaded.append(load_run(r, lab))
    seen: dict[str, int] = {}
    for r in loaded:  # two folders of one name stay apart
        seen[r.label] = seen.get(r.label, 0) + 1
        if seen[r.label] > 1:
            r.label = f"{r.label} ({seen[r.label]})"
    have = set().union(*(_derived_columns(r.signals) for r in loaded))
    if signals:
        missing = [s for s in signals if s not in have]
        if missing:
            raise ConfigError("signals", f"no run has {missing[0]!r}")
        panels = [(s, (s,)) for s in signals]
    else:
        panels = [(q, cols) for q, cols in DEFAULT_PANELS if have & set(cols)]
    return Comparison(loaded, panels)
