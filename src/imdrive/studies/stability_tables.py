"""The result tables of ``docs/stability.md``, measured with :mod:`imdrive.stability` and
rendered by :mod:`imdrive.studies.doctables` (``python -m imdrive.studies.doctables --run
NAME``).

Every measurement is on the ``sensorless`` preset; the first three on the paper tuning of the
MRAS (``wc = 5 rad/s``, 40 Hz, :data:`PAPER_TUNING`), on which the page's first sections were
measured. The grids:

* the low-speed map: 0–300 rpm × −24…24 N m, 50 × 40 points (:data:`LOW_SPEEDS`,
  :data:`LOW_TORQUES`); "unstable points" counts the points whose steady state is unstable;
* the R̂1/R1 limit: the largest ratio for which every point of a speed set at one load is
  stable, by bisection between 1 and 1.5 (12 steps, :func:`r1_limit`); the lower limit the same
  downwards to 0.5.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from imdrive.config.scenario import Scenario
from imdrive.studies.doctable import DocTable, register

PAPER_TUNING = ("mras.wc_rad_s=5", "mras.bandwidth_Hz=40")
LOW_SPEEDS = np.linspace(0.0, 300.0, 50)
LOW_TORQUES = np.linspace(-24.0, 24.0, 40)
BISECTION_STEPS = 12


def _sensorless(overrides=()) -> Scenario:
    # these tables are the type-1 MRAS's (the maps linearise the type-2 one too since round 4);
    # at a 10 Hz bandwidth the machine-dependent default would turn the type-2 adaptation on
    # (config/perunit.py mras_ramp_lag_pu)
    return Scenario.read("sensorless", ["mras.acceleration_tracking=false", *overrides])


def r1_limit(sc: Scenario, speeds, torque: float, lo: float = 1.0, hi: float = 1.5) -> float:
    """The R̂1/R1 ratio between ``lo`` (stable) and ``hi`` where the map at ``speeds`` ×
    ``torque`` stops being stable everywhere, by bisection; ``hi`` itself if still stable
    there, ``lo`` if not stable at ``lo`` (``hi < lo`` searches downwards)."""
    from imdrive.stability import stability_map

    def ok(r):
        return bool(stability_map(sc, speeds, [torque], R1_ratio=r).stable.all())

    if not ok(lo):
        return lo
    if ok(hi):
        return hi
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


def unstable_points(sc: Scenario) -> int:
    """Points of the low-speed map whose steady state is unstable (exact parameters; points
    without a steady state, e.g. beyond the current limit, are not counted)."""
    from imdrive.stability import stability_map

    df = stability_map(sc, LOW_SPEEDS, LOW_TORQUES)
    return int(((df.status == "ok") & ~df.stable).sum())


# ---------------------------------------------------------------------------------------------
# the map against simulation


def measure_validation() -> pd.DataFrame:
    """:func:`~imdrive.stability.validate_map` on 9 speeds × 9 torques × R̂1/R1 ∈ {1, 1.06,
    1.1} (the paper tuning): one row per point."""
    from imdrive.stability import validate_map

    speeds = [10, 20, 40, 60, 100, 200, 500, 1000, 1400]
    torques = [-18, -13.5, -9, -4.5, 0, 4.5, 9, 13.5, 18]
    table, _ = validate_map(_sensorless(PAPER_TUNING), speeds, torques, (1.0, 1.06, 1.1))
    cols = ["speed_rpm", "torque_Nm", "R1_ratio", "status", "stable", "sim_stable"]
    return table[[*cols, "max_real_1_per_s", "sim_growth_1_per_s", "near_boundary"]]


def render_validation(df) -> list[str]:
    have = df[df.status == "ok"]
    out = ["| | sim stable | sim unstable |", "|---|---:|---:|"]
    for label, verdict in (("map stable", True), ("map unstable", False)):
        row = have[have.stable == verdict]
        out.append(f"| {label} | {int(row.sim_stable.sum())} | {int((~row.sim_stable).sum())} |")
    miss = have[have.stable != have.sim_stable]
    where = "; ".join(
        (
            f"{r.speed_rpm:g} rpm, {r.torque_Nm:g} N m, R̂1/R1 = {r.R1_ratio:.3g}: "
            f"Re s = {r.max_real_1_per_s:.2g} 1/s"
        ).replace("-", "−")
        + (", on the boundary" if r.near_boundary else "")
        for r in miss.itertuples()
    )
    out += [
        "",
        f"{len(have)} points with a steady state, "
        f"{100 * (1 - len(miss) / len(have)):.1f} % agreement"
        + (f"; misses: {where}." if len(miss) else "."),
    ]
    return out


# ---------------------------------------------------------------------------------------------
# MRAS cut-off and gains (one setting changed from the paper tuning)

SETTINGS = {
    "wc = 1 rad/s": ["mras.wc_rad_s=1"],
    "wc = 5 rad/s (paper tuning)": [],
    "wc = 20 rad/s": ["mras.wc_rad_s=20"],
    "MRAS bandwidth 10 Hz": ["mras.bandwidth_Hz=10"],
    "MRAS bandwidth 20 Hz": ["mras.bandwidth_Hz=20"],
    "MRAS bandwidth 40 Hz (paper tuning)": [],
    "MRAS bandwidth 80 Hz": ["mras.bandwidth_Hz=80"],
    "speed loop 2 Hz": ["control.speed_bandwidth_Hz=2"],
    "speed loop 10 Hz": ["control.speed_bandwidth_Hz=10"],
}


def measure_settings() -> pd.DataFrame:
    """For each setting of :data:`SETTINGS` (on the paper tuning): the unstable points of the
    low-speed map and the R̂1/R1 limit at 1000 rpm, 12 N m."""
    rows = []
    for label, ov in SETTINGS.items():
        sc = _sensorless([*PAPER_TUNING, *ov])
        speed_loop = label.startswith("speed loop")
        rows.append(
            {
                "setting": label,
                "unstable_points": np.nan if speed_loop else unstable_points(sc),
                "grid_points": LOW_SPEEDS.size * LOW_TORQUES.size,
                "R1_limit_1000rpm_12Nm": r1_limit(sc, [1000.0], 12.0),
            }
        )
    return pd.DataFrame(rows)


def render_settings(df) -> list[str]:
    n = int(df.grid_points.iloc[0])
    out = [
        f"| setting (others: the paper tuning) | unstable points, 0–300 rpm × ±24 N m (of {n}) "
        "| R̂1/R1 limit at 1000 rpm, 12 N m |",
        "|---|---:|---:|",
    ]
    for r in df.itertuples():
        pts = "–" if np.isnan(r.unstable_points) else f"{r.unstable_points:.0f}"
        out.append(f"| {r.setting} | {pts} | {r.R1_limit_1000rpm_12Nm:.3f} |")
    return out


# ---------------------------------------------------------------------------------------------
# the search behind the default tuning

CANDIDATES = (
    (5, 40, 5),
    (10, 20, 5),
    (15, 20, 5),
    (20, 20, 5),
    (15, 40, 5),
    (20, 40, 5),
    (10, 40, 2),
    (15, 20, 3),
)


#: the candidates the page names
LABELS = {(5, 40, 5): " (paper tuning)", (15, 20, 5): " (the default)"}


def measure_candidates(candidates=CANDIDATES) -> pd.DataFrame:
    """For each ``(wc, MRAS bandwidth, speed bandwidth)``: the R̂1/R1 limits over 150–1500 rpm
    (every 50 rpm) at 12, 0 and −12 N m, the lower limit at 12 N m, the unstable points of the
    low-speed map and the unstable speeds at −12 N m (0–300 rpm, 1 rpm steps: the band's
    lowest and highest unstable speed)."""
    from imdrive.stability import stability_map

    speeds = np.arange(150.0, 1501.0, 50.0)
    rows = []
    for wc, bw, sbw in candidates:
        sc = _sensorless(
            [f"mras.wc_rad_s={wc}", f"mras.bandwidth_Hz={bw}", f"control.speed_bandwidth_Hz={sbw}"]
        )
        regen = stability_map(sc, np.arange(0.0, 301.0, 1.0), [-12.0])
        bad = regen.speed_rpm[(regen.status == "ok") & ~regen.stable]
        row = {"wc_rad_s": wc, "mras_Hz": bw, "speed_Hz": sbw}
        for torque in (12.0, 0.0, -12.0):
            row[f"R1_limit_{torque:g}Nm".replace("-", "m")] = r1_limit(sc, speeds, torque)
        row["R1_lower_limit_12Nm"] = r1_limit(sc, speeds, 12.0, lo=1.0, hi=0.5)
        row["unstable_points"] = unstable_points(sc)
        row["regen_unstable_min_rpm"] = bad.min() if len(bad) else np.nan
        row["regen_unstable_max_rpm"] = bad.max() if len(bad) else np.nan
        rows.append(row)
    return pd.DataFrame(rows)


def render_candidates(df) -> list[str]:
    out = [
        "| wc (rad/s) | MRAS (Hz) | speed (Hz) | R̂1/R1 limit, 150–1500 rpm, 12 / 0 / −12 N m "
        "| lower limit | unstable points of 2000 | regenerating −12 N m unstable |",
        "|---:|---:|---:|---|---:|---:|---|",
    ]
    for r in df.itertuples():
        lims = f"{r.R1_limit_12Nm:.3f} / {r.R1_limit_0Nm:.3f} / {r.R1_limit_m12Nm:.3f}"
        lims += LABELS.get((r.wc_rad_s, r.mras_Hz, r.speed_Hz), "")
        low = "< 0.5" if r.R1_lower_limit_12Nm <= 0.5 else f"{r.R1_lower_limit_12Nm:.3f}"
        band = (
            "none"
            if np.isnan(r.regen_unstable_min_rpm)
            else f"{r.regen_unstable_min_rpm:.0f}–{r.regen_unstable_max_rpm:.0f} rpm"
        )
        out.append(
            f"| {r.wc_rad_s:g} | {r.mras_Hz:g} | {r.speed_Hz:g} | {lims} | {low} "
            f"| {r.unstable_points:.0f} | {band} |"
        )
    return out


# ---------------------------------------------------------------------------------------------
# the ringing during the start-up ramp


def measure_ringing(speeds=(50.0, 150.0, 300.0, 500.0), torque: float = 5.0) -> pd.DataFrame:
    """The least damped oscillatory mode (above 0.5 Hz) of the linearised ``sensorless`` drive
    (default tuning) at ``speeds`` × ``torque``, with the stator frequency of the point."""
    from imdrive.stability import operating_point

    sc = _sensorless()
    m = sc.machine
    rows = []
    for speed in speeds:
        op = operating_point(sc, speed, torque)
        i_dq = op.current_dq_A
        f_s = m.pole_pairs * op.speed_rpm / 60.0 + i_dq.imag / i_dq.real / m.T2_s / (2 * np.pi)
        mode = max((x for x in op.modes() if x.frequency_Hz > 0.5), key=lambda x: x.s.real)
        rows.append(
            {
                "speed_rpm": speed,
                "torque_Nm": torque,
                "stator_frequency_Hz": f_s,
                "mode_frequency_Hz": mode.frequency_Hz,
                "real_1_per_s": mode.s.real,
                "damping": mode.damping,
            }
        )
    return pd.DataFrame(rows)


def render_ringing(df) -> list[str]:
    out = ["| speed | stator frequency | mode | Re s | damping |", "|---|---|---|---|---|"]
    for r in df.itertuples():
        out.append(
            f"| {r.speed_rpm:g} rpm | {r.stator_frequency_Hz:.1f} Hz "
            f"| {r.mode_frequency_Hz:.1f} Hz | {r.real_1_per_s:.1f} /s "
            f"| {r.damping:.2f} |".replace("-", "−")
        )
    return out


for _name, _data, _render, _measure in (
    ("map-validation", "stability_validation", render_validation, measure_validation),
    ("mras-settings", "stability_settings", render_settings, measure_settings),
    ("default-tuning", "stability_candidates", render_candidates, measure_candidates),
    ("ramp-ringing", "stability_ringing", render_ringing, measure_ringing),
):
    register(DocTable(_name, "stability.md", f"data/{_data}.csv", _render, _measure))
