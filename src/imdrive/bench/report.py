"""Run the protocol on the batch engine and write ``estimators.csv``, one figure per metric
and ``estimators.md`` (:func:`bench_estimators`)."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from imdrive.bench.metrics import METRICS, run_metrics
from imdrive.bench.protocol import CASES, ESTIMATORS, protocol, scenario
from imdrive.config.plugins import allowing_plugins
from imdrive.errors import ConfigError

UNITS = {
    "steady_speed_error_rpm": "rpm",
    "rms_speed_error_rpm": "rpm",
    "speed_est_error_rpm": "rpm",
    "rms_speed_est_error_rpm": "rpm",
    "R2_error_pct": "%",
    "R2_time_to_2pct_s": "s",
    "peak_current_A": "A",
    "lost_control": "",
}


def run_protocol(
    quick: bool = False,
    parallel: bool = True,
    runs=None,
    estimators=None,
    cases=None,
    drives=None,
    overrides=(),
    *,
    allow_plugins: bool | None = None,
):
    """Simulate every run of the protocol.

    Parameters
    ----------
    quick : bool
        The quick subset of the protocol (:func:`~imdrive.bench.protocol.protocol`).
    parallel : bool
        Run the batch on all cores.
    runs : list of Run, optional
        Runs (:class:`~imdrive.bench.protocol.Run`) in place of the protocol.
    estimators : dict, optional
        Estimator configurations beside the protocol's (name -> overrides; see
        :func:`~imdrive.bench.protocol.scenario`); without ``runs``, the protocol compares
        exactly these.
    cases : dict, optional
        Cases beside the protocol's (name -> :class:`~imdrive.bench.protocol.Case`); without
        ``runs``, exactly these.
    drives : dict, optional
        Drives beside the protocol's (name -> preset or scenario file); without ``runs``,
        exactly these.
    overrides : iterable of str
        Overrides of every drive (``key=value``), applied before the estimator's and the
        case's.
    allow_plugins : bool, optional
        True: import the modules a configuration lists in ``plugins.modules`` (their code
        runs); default: only with ``IMDRIVE_ALLOW_PLUGINS=1`` (:mod:`imdrive.config.plugins`).

    Returns
    -------
    table : pandas.DataFrame
        Columns ``estimator, case, drive, diverged`` and the
        :data:`~imdrive.bench.metrics.METRICS`, one row per run.
    results : list of SimulationResult
        The runs' results, in the order of the rows.
    wall_s : float
        Wall time of the batch, s.
    """
    import pandas as pd

    from imdrive.run.batch import simulate_batch

    def names(d):
        return None if d is None else list(d)

    if runs is None:
        runs = protocol(quick, names(estimators), names(cases), names(drives))
    runs = list(runs)
    all_cases = {**CASES, **(cases or {})}
    t0 = time.perf_counter()
    with allowing_plugins(allow_plugins):
        scenarios = [scenario(r, estimators, cases, drives, overrides) for r in runs]
    res = simulate_batch(scenarios, logs=True, parallel=parallel)
    wall = time.perf_counter() - t0
    rows = []
    for r, sim in zip(runs, res.results, strict=True):
        m = run_metrics(sim.signals, all_cases[r.case].t_eval_s, sim.diverged)
        rows.append({"estimator": r.estimator, "case": r.case, "drive": r.drive,
                     "diverged": bool(sim.diverged), **m})  # fmt: skip
    return pd.DataFrame(rows), res.results, wall


def _fmt(v) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "**lost**" if v else "ok"
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return f"{v:.3g}"


def _estimators_of(table) -> list[str]:
    """The table's estimator configurations: the protocol's in its order, then the others."""
    present = list(dict.fromkeys(table["estimator"]))
    return [e for e in ESTIMATORS if e in present] + [e for e in present if e not in ESTIMATORS]


def markdown(table) -> str:
    """One Markdown table per metric and drive: cases down, estimator configurations across.

    Parameters
    ----------
    table : pandas.DataFrame
        The table of :func:`run_protocol`.

    Returns
    -------
    str
        The Markdown text.
    """
    ests = _estimators_of(table)
    out = ["# Estimator bench", ""]
    for drive in dict.fromkeys(table["drive"]):
        sub = table[table["drive"] == drive]
        for met in METRICS:
            unit = f" ({UNITS[met]})" if UNITS[met] else ""
            out += [f"## {met}{unit}, {drive} drive", ""]
            out.append("| case | " + " | ".join(ests) + " |")
            out.append("|---|" + "---|" * len(ests))
            for case in dict.fromkeys(sub["case"]):
                cells = []
                for e in ests:
                    v = sub[(sub["case"] == case) & (sub["estimator"] == e)][met]
                    cells.append(_fmt(v.iloc[0]) if len(v) else "–")
                out.append(f"| {case} | " + " | ".join(cells) + " |")
            out.append("")
    return "\n".join(out)


def figures(table, out: Path) -> list[Path]:
    """One grouped bar chart per metric (cases along x, a bar per estimator, a panel per drive).

    Parameters
    ----------
    table : pandas.DataFrame
        The table of :func:`run_protocol` (the same numbers as the CSV).
    out : pathlib.Path
        Folder to write ``<metric>.png`` into.

    Returns
    -------
    list of pathlib.Path
        The PNG files written.
    """
    from imdrive._figure import new_figure

    ests = _estimators_of(table)
    drives = list(dict.fromkeys(table["drive"]))
    paths = []
    for met in METRICS:
        fig = new_figure(figsize=(11, 3.2 * len(drives)), layout="constrained")
        axes = fig.subplots(len(drives), 1, squeeze=False)
        for ax, drive in zip(axes[:, 0], drives, strict=True):
            sub = table[table["drive"] == drive]
            cases = list(dict.fromkeys(sub["case"]))
            x = np.arange(len(cases))
            wd = 0.8 / len(ests)
            for j, e in enumerate(ests):
                vals = []
                for c in cases:
                    v = sub[(sub["case"] == c) & (sub["estimator"] == e)][met]
                    vals.append(float(v.iloc[0]) if len(v) else np.nan)
                ax.bar(x + (j - (len(ests) - 1) / 2) * wd, vals, wd, label=e)
            ax.set_xticks(x, cases, rotation=20, fontsize=8)
            ax.set_title(f"{drive} drive", fontsize=9)
            ax.set_ylabel(f"{met} ({UNITS[met]})" if UNITS[met] else met, fontsize=8)
            ax.axhline(0.0, color="k", lw=0.5)
            if met not in ("lost_control", "peak_current_A", "R2_time_to_2pct_s"):
                ax.set_yscale("symlog", linthresh=0.1)
        axes[0, 0].legend(fontsize=7, ncol=len(ests))
        p = out / f"{met}.png"
        fig.savefig(p, dpi=90)
        paths.append(p)
    return paths


def bench_estimators(
    out_dir,
    quick: bool = False,
    estimators=None,
    cases=None,
    drives=None,
    overrides=(),
    parallel: bool = True,
    *,
    allow_plugins: bool | None = None,
) -> dict:
    """Run the protocol and write ``estimators.csv``, ``<metric>.png``, ``estimators.md``.

    Parameters
    ----------
    out_dir : str or pathlib.Path
        Folder to write (replaced as a whole, :func:`imdrive._io.replace_folder`; nothing is
        written when the input is refused or a run fails to build).
    quick : bool
        The quick subset of the protocol.
    estimators, cases, drives, overrides
        As :func:`run_protocol` (``imdrive bench-estimators --estimators``, ``--speeds`` and
        ``--loads``, ``--base``, ``--set``); ``estimators`` may also be a list of the
        protocol's configuration names.
    parallel : bool
        Run the batch on all cores.
    allow_plugins : bool, optional
        As :func:`run_protocol`.

    Returns
    -------
    dict
        ``runs`` (count), ``wall_s`` (s), ``csv``, ``markdown`` and ``figures`` (paths).
    """
    from imdrive._io import replace_folder

    out = Path(out_dir)
    if estimators is not None and not isinstance(estimators, dict):
        if isinstance(estimators, str):
            estimators = [estimators]
        estimators = list(estimators)
        unknown = [e for e in estimators if e not in ESTIMATORS]
        if unknown:
            raise ConfigError(
                "estimators", f"no configuration {unknown[0]!r}; known: {', '.join(ESTIMATORS)}"
            )
        estimators = {e: ESTIMATORS[e] for e in estimators}
    if estimators is not None and not estimators:
        raise ConfigError("estimators", f"is empty: name one or more of {', '.join(ESTIMATORS)}")
    table, _, wall = run_protocol(
        quick,
        parallel,
        estimators=estimators,
        cases=cases,
        drives=drives,
        overrides=overrides,
        allow_plugins=allow_plugins,
    )
    # the folder as a whole, staged and swapped in (as imdrive run writes its own): a failure
    # leaves no folder, or the earlier one, never a partial estimators.csv
    with replace_folder(out) as staging:
        table.to_csv(staging / "estimators.csv", index=False)
        figs = figures(table, staging)
        (staging / "estimators.md").write_text(markdown(table) + "\n")
    figs = [out / Path(f).name for f in figs]
    return {
        "runs": len(table),
        "wall_s": wall,
        "csv": out / "estimators.csv",
        "markdown": out / "estimators.md",
        "figures": figs,
    }
