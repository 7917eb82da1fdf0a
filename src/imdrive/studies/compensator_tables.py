"""The three compensators within 50-1400 rpm, for
``docs/envelope.md`` ("Within 50–1400 rpm: the three compensators"), measured here and rendered
by :mod:`imdrive.studies.doctables` (``python -m imdrive.studies.doctables --run NAME``).

* :func:`measure_compensators` runs the ``envelope`` sweep (``sweep/presets/envelope.toml``:
  speed × load × R̂2(0)/R2 × R̂1/R1 × variant uncompensated / paper / injection), keeps the
  columns the tables read (:data:`KEEP`) and copies its heatmaps into ``docs/figures/envelope``;
  :func:`render_compensators` (the share of the cells of the drive's stable region that
  converge, by variant and speed) and :func:`render_misses` (the injection variant's cells that
  do not) read it, with the definitions of :func:`classify`.
* :func:`measure_off_grid` runs the injection variant at points off the sweep's grid
  (:data:`OFF_GRID`), with the uncompensated drive there for the stable region;
  :func:`render_off_grid`.

The adaptive law's gain table (``adaptive-gains``) went with that law in 0.2.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from imdrive.studies.doctable import DOCS, DocTable, register

SWEEP = "envelope"
FIG_DIR = DOCS / "figures" / "envelope"
AXES = ("speed_rpm", "load_Nm", "R2_ratio", "R1_ratio", "variant")
KEEP = (
    "run",
    *AXES,
    "diverged",
    "lost_control",
    "convergence_time_s",
    "R2_error_pct",
    "speed_error_rpm",
)
VARIANTS = ("uncompensated", "paper", "injection")
#: converged: R̂2 within this of R2 (%) ...
R2_GOAL_PCT = 2.0
#: ... by this time (s; the compensators start at 4 s) and from then on
CONVERGED_BY_S = 14.0
#: and the mean speed error over the last 0.5 s below this (rpm)
SPEED_GOAL_RPM = 1.0
#: the injection variant's goal: this share of the cells inside the stable region converge
SHARE_GOAL = 0.95
#: points off the sweep's grid (nobody tuned for them): speed, load, R̂2(0)/R2, R̂1/R1
OFF_GRID = {
    "speed_rpm": (75.0, 200.0, 450.0, 800.0, 1200.0),
    "load_Nm": (-9.0, -3.0, 3.0, 9.0),
    "R2_ratio": (0.85, 1.15),
    "R1_ratio": (0.95, 1.05),
}


def _minus(text: str) -> str:
    """``text`` with true minus signs, as the pages write them."""
    return text.replace("-", "−")


def _flag(s: pd.Series) -> pd.Series:
    return s.fillna(False).astype(bool)


def classify(df: pd.DataFrame) -> pd.DataFrame:
    """``df`` with the columns ``inside`` and ``ok``.

    ``inside``: the run's (speed, load, R̂1/R1) point is in the drive's stable region, where
    the uncompensated drive with R̂2 = R2 neither diverges nor loses control. ``ok``: R̂2
    within :data:`R2_GOAL_PCT` of R2 by :data:`CONVERGED_BY_S` and from then on, the speed error
    under :data:`SPEED_GOAL_RPM`, and control kept.
    """
    key = ["speed_rpm", "load_Nm", "R1_ratio"]
    base = df[(df["variant"] == "uncompensated") & np.isclose(df["R2_ratio"], 1.0)]
    stable = ~(_flag(base["lost_control"]) | _flag(base["diverged"]))
    region = {tuple(k) for k, s in zip(base[key].to_numpy(), stable, strict=True) if s}
    out = df.copy()
    out["inside"] = [tuple(k) in region for k in out[key].to_numpy()]
    converged = (out["convergence_time_s"] <= CONVERGED_BY_S) & (
        out["R2_error_pct"].abs() <= R2_GOAL_PCT
    )
    out["ok"] = (
        converged
        & (out["speed_error_rpm"].abs() < SPEED_GOAL_RPM)
        & ~_flag(out["lost_control"])
        & ~_flag(out["diverged"])
    )
    return out


def measure_compensators(store: Path | None = None, figures: Path = FIG_DIR) -> pd.DataFrame:
    """Run the ``envelope`` sweep into ``store`` (default a temporary folder), copy its heatmaps
    into ``figures`` and return its :data:`KEEP` columns, one row per run."""
    from imdrive.sweep import load_sweep, run_sweep

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(store) if store is not None else Path(tmp) / SWEEP
        df = run_sweep(load_sweep(SWEEP), folder, report=False)
        figures.mkdir(parents=True, exist_ok=True)
        for png in sorted((folder / "figures").glob("*.png")):
            shutil.copyfile(png, figures / png.name)
    out = df[list(KEEP)].copy()
    for col in ("convergence_time_s", "R2_error_pct", "speed_error_rpm"):
        out[col] = out[col].astype(float).round(6)
    return out


def _share(ok: pd.Series) -> str:
    return "–" if len(ok) == 0 else f"{ok.mean():.2f}".replace("0.00", "0").replace("1.00", "1")


def render_compensators(df: pd.DataFrame) -> list[str]:
    """The share of the cells inside the stable region that converge, by variant (and by
    speed), the share without the lowest speed, the runs that lost control and the median
    speed error, then one line on the stable region."""
    c = classify(df)
    speeds = sorted(c["speed_rpm"].unique())
    low = speeds[0]
    by = " / ".join(f"{s:g}" for s in speeds)
    out = [
        f"| variant | within goal | by speed {by} rpm | without {low:g} rpm | lost control "
        "| median \\|speed error\\| |",
        "|---|---|---|---|---|---|",
    ]
    for v in VARIANTS:
        g = c[(c["variant"] == v) & c["inside"]]
        n_ok = int(g["ok"].sum())
        cell = f"{n_ok} of {len(g)} ({100 * g['ok'].mean():.1f} %)"
        cell = f"**{cell}**" if v == "injection" else cell
        per = " / ".join(_share(g[g["speed_rpm"] == s]["ok"]) for s in speeds)
        rest = g[g["speed_rpm"] != low]
        lost = _flag(g["lost_control"]).sum()
        med = float(np.nanmedian(g["speed_error_rpm"].abs())) if len(g) else np.nan
        out.append(
            f"| {v} | {cell} | {per} | {100 * rest['ok'].mean():.1f} % "
            f"| {int(lost)} | {med:.2f} rpm |"
        )
    base = c[(c["variant"] == "uncompensated") & np.isclose(c["R2_ratio"], 1.0)]
    outside = base[~base["inside"]]
    where = ", ".join(
        f"{s:g} rpm, {load:g} N m".replace("-", "−")
        for (s, load) in dict.fromkeys(zip(outside["speed_rpm"], outside["load_Nm"], strict=True))
    )
    inj = c[(c["variant"] == "injection") & c["inside"]]
    met = "met" if len(inj) and inj["ok"].mean() >= SHARE_GOAL else "**not met**"
    out += [
        "",
        f"Stable region: {int(base['inside'].sum())} of {len(base)} (speed, load, R̂1/R1) "
        f"points; outside: {where or 'none'}. Cells per variant: {len(inj)}. The injection "
        f"variant's goal, {100 * SHARE_GOAL:.0f} % of them: {met}.",
    ]
    return out


def measure_off_grid() -> pd.DataFrame:
    """The injection variant of the ``envelope`` sweep at the points of :data:`OFF_GRID`, with
    the uncompensated drive at R̂2 = R2 for the stable region; the columns of
    :func:`measure_compensators` (``run`` the row's index)."""
    from itertools import product

    from imdrive.run.batch import simulate_batch
    from imdrive.sweep import load_sweep

    sweep = load_sweep(SWEEP)
    g = OFF_GRID
    points = [
        (s, load, r2, r1, "injection")
        for s, load, r2, r1 in product(g["speed_rpm"], g["load_Nm"], g["R2_ratio"], g["R1_ratio"])
    ]
    points += [
        (s, load, 1.0, r1, "uncompensated")
        for s, load, r1 in product(g["speed_rpm"], g["load_Nm"], g["R1_ratio"])
    ]
    batch = simulate_batch([sweep.scenario_for(p) for p in points], window_s=sweep.window_s)
    m = batch.metrics
    out = pd.DataFrame(points, columns=list(AXES))
    out.insert(0, "run", range(len(out)))
    for col in KEEP[len(AXES) + 1 :]:
        out[col] = m[col].to_numpy()
    for col in ("convergence_time_s", "R2_error_pct", "speed_error_rpm"):
        out[col] = out[col].astype(float).round(6)
    return out


def render_off_grid(df: pd.DataFrame) -> list[str]:
    """The injection variant's cells within goal off the grid, by speed and load (of the
    cells inside the stable region), then the cells that miss (:func:`render_misses`)."""
    c = classify(df)
    inj = c[(c["variant"] == "injection") & c["inside"]]
    loads = sorted(c["load_Nm"].unique())
    out = [
        "| speed, rpm | " + " | ".join(_minus(f"{x:g} N m") for x in loads) + " | all |",
        "|---|" + "---|" * (len(loads) + 1),
    ]

    def count(g):
        return f"{int(g['ok'].sum())} of {len(g)}"

    for s in sorted(c["speed_rpm"].unique()):
        row = inj[inj["speed_rpm"] == s]
        cells = [count(row[row["load_Nm"] == x]) for x in loads]
        out.append(f"| {s:g} | " + " | ".join(cells) + f" | {count(row)} |")
    cells = [count(inj[inj["load_Nm"] == x]) for x in loads]
    share = f"{100 * inj['ok'].mean():.1f} %" if len(inj) else "–"
    out.append("| all | " + " | ".join(cells) + f" | **{count(inj)} ({share})** |")
    if (~inj["ok"]).any():
        out += ["", "The cells that miss:", "", *render_misses(df)]
    return out


def render_misses(df: pd.DataFrame) -> list[str]:
    """The injection variant's cells inside the stable region that miss, grouped by speed,
    load and R̂2(0)/R2 (the R̂1/R1 values that miss in one row)."""
    c = classify(df)
    miss = c[(c["variant"] == "injection") & c["inside"] & ~c["ok"]]
    out = [
        "| speed, rpm | load, N m | R̂2(0)/R2 | R̂1/R1 | final R̂2 error, % | converged at, s "
        "| speed error, rpm | lost control |",
        "|---|---|---|---|---|---|---|---|",
    ]
    if miss.empty:
        return [*out, "| none | | | | | | | |"]

    def span(v, fmt):
        v = np.asarray(v, float)
        if np.all(np.isnan(v)):
            return "never" if fmt == ".1f" else "–"
        lo, hi = np.nanmin(v), np.nanmax(v)
        text = f"{lo:{fmt}}" if lo == hi else f"{lo:{fmt}} … {hi:{fmt}}"
        return text.replace("-", "−")

    for (s, load, r2), g in miss.groupby(["speed_rpm", "load_Nm", "R2_ratio"], sort=True):
        out.append(
            f"| {s:g} | {load:+g} | {r2:g} | {', '.join(f'{x:g}' for x in g['R1_ratio'])} "
            f"| {span(g['R2_error_pct'], '+.1f')} | {span(g['convergence_time_s'], '.1f')} "
            f"| {span(g['speed_error_rpm'], '+.2f')} "
            f"| {int(_flag(g['lost_control']).sum())} of {len(g)} |".replace("+0 ", "0 ")
        )
    return [line.replace("| -", "| −") for line in out]


register(
    DocTable(
        "envelope-compensators",
        "envelope.md",
        "data/envelope_compensators.csv",
        render_compensators,
        measure_compensators,
    )
)
register(
    DocTable(
        "envelope-misses",
        "envelope.md",
        "data/envelope_compensators.csv",
        render_misses,
        None,
        "python -m imdrive.studies.doctables --run envelope-compensators",
    )
)
register(
    DocTable(
        "envelope-off-grid",
        "envelope.md",
        "data/envelope_off_grid.csv",
        render_off_grid,
        measure_off_grid,
    )
)
