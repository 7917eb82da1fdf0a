"""Regenerating at low speed, by stator frequency: where the sensorless drive and the R2
tracking hold, on machines of different rated slip.

The machine envelope (:mod:`imdrive.studies.machines`) puts its lowest speed at 5 % of each
machine's rated speed. Regenerating the rated torque there, the stator frequency ``f_s =
(n_p w_m + w_sl)/2 pi`` (``w_sl < 0``) is near zero on a machine whose rated slip is about 5 %
(Table IV +0.36 Hz, Krause 50 hp +0.18 Hz with R2_hat = R2) and a few hertz on the large,
low-slip ones (Krause 500 hp +2.1 Hz). At ``f_s = 0`` neither the speed nor R2 can be told
from the fundamental-frequency voltages and currents (Holtz, "Sensorless control of induction
motor drives", Proc. IEEE 90(8), 2002): the grid in per-unit of speed compares the small
machines on that line with the large ones away from it.

This study puts every machine at the same stator frequencies instead: regenerating the rated
torque, the speed reference is the one whose steady state with ``R2_hat = R2`` runs at
``f_s`` (:func:`speed_for_stator_frequency`, from :func:`imdrive.analysis.foc_operating_point`),
for ``f_s`` in :data:`F_S_HZ`, from ``R2_hat(0)/R2`` in :data:`R2_RATIOS`. The runs, the
timeline and the verdicts are the machine envelope's (:func:`imdrive.studies.machines.measure`,
:func:`~imdrive.studies.machines.verdict`).

``python -m imdrive.studies.doctables --run zero-frequency`` measures it again and rewrites
its table in docs/machine-envelope.md.
"""

from __future__ import annotations

import math
import warnings

import pandas as pd
from scipy.optimize import brentq

from imdrive.config.machine import rated_point
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning
from imdrive.studies import machines as envelope

#: Machines: the paper's (4.4 % rated slip), two of other sizes near 5 % and 2.9 %
#: (Krause 50 hp, Aalto 2.2 kW) and a large low-slip one (Krause 500 hp, 1.5 %).
MACHINES = ("paper-table-iv", "krause-50hp", "aalto-2.2kw", "krause-500hp")
#: Stator frequencies of the steady state with R2_hat = R2, Hz.
F_S_HZ = (-0.5, -0.25, 0.0, 0.25, 0.5, 1.0, 2.0)
#: Starting R2_hat(0)/R2.
R2_RATIOS = (0.8, 1.0, 1.2)
#: Load in per-unit of the rated torque (negative: regenerating).
LOAD_PU = -1.0
#: The machine envelope's drives and ``injection-robust`` on the adaptive full-order
#: observer (``injection-robust-afo``): since the standstill R1 test serves every estimator
#: (kernels/r1_standstill.py) the observer runs on an identified R1, and it held all 84 runs
#: where the MRAS lost 19 (2026-11-29).
DRIVES = (*envelope.DRIVES, "injection-robust-afo")
#: The drives whose R2_hat error at the end the table gives.
R2_DRIVES = ("injection-robust", "injection-robust-afo")


def speed_for_stator_frequency(sc, f_s_Hz: float, load_Nm: float) -> float:
    """The speed reference, rpm, whose field-oriented steady state with ``R2_hat = R2`` runs
    at the stator frequency ``f_s_Hz`` with the load ``load_Nm``
    (:func:`imdrive.studies.machines.stator_frequency_Hz`, which rises with the speed).

    Raises
    ------
    ValueError
        If no speed between minus and plus the rated speed gives ``f_s_Hz``.
    """
    n_rated = rated_point(sc.machine).speed_rpm

    def gap(n):
        return envelope.stator_frequency_Hz(sc, n, load_Nm, 1.0) - f_s_Hz

    lo, hi = -n_rated, n_rated
    if gap(lo) * gap(hi) > 0.0:
        raise ValueError(f"f_s_Hz: no speed within +-{n_rated:.0f} rpm runs at {f_s_Hz} Hz")
    return float(brentq(gap, lo, hi, xtol=1e-9))


def scenarios(machines=MACHINES, frequencies=F_S_HZ, ratios=R2_RATIOS, drives=None):
    """The study's scenarios and rows (those of :func:`imdrive.studies.machines.scenarios`,
    with ``f_s_target_Hz``), one machine's speeds at a time; ``drives`` default
    :data:`DRIVES`."""
    all_scs, tables = [], []
    for m in machines:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConfigWarning)
            base = Scenario.read("sensorless", [f'machine.preset="{m}"'])
        rp = rated_point(base.machine)
        T = LOAD_PU * rp.torque_Nm
        speeds = [speed_for_stator_frequency(base, f, T) / rp.speed_rpm for f in frequencies]
        scs, table = envelope.scenarios(
            [m], drives=drives or DRIVES, speeds=speeds, loads=(LOAD_PU,), ratios=ratios
        )
        table["f_s_target_Hz"] = table["speed_pu"].map(dict(zip(speeds, frequencies, strict=True)))
        all_scs += scs
        tables.append(table)
    return all_scs, pd.concat(tables, ignore_index=True)


def run(machines=MACHINES, frequencies=F_S_HZ, ratios=R2_RATIOS) -> pd.DataFrame:
    """Run the study: one row per drive, the machine envelope's columns and ``f_s_target_Hz``."""
    return envelope.measure(*scenarios(machines, frequencies, ratios))


def markdown_lines(df: pd.DataFrame) -> list[str]:
    """The table: per machine and stator frequency, the speed reference and, per drive, the
    runs converged / not converged / lost over the starting R2_hat; for each drive of
    :data:`R2_DRIVES` the R2_hat error at the end, lowest to highest."""
    drives = list(dict.fromkeys(df["drive"]))
    r2_drives = [d for d in R2_DRIVES if d in drives]
    head = "| machine | f_s, Hz | speed, rpm (% rated) | " + " | ".join(
        f"{d}: converged / not / lost" for d in drives
    )
    head += "".join(f" | {d}: R̂2 error at the end, %" for d in r2_drives)
    lines = [head + " |"]
    lines.append("|---|---|---|" + "---|" * (len(drives) + len(r2_drives)))
    for (m, f), g in df.groupby(["machine", "f_s_target_Hz"], sort=False):
        n, rated = float(g["speed_rpm"].iloc[0]), float(g["rated_speed_rpm"].iloc[0])
        cells = [m, f"{f:+.2f}", f"{n:.1f} ({100 * n / rated:.1f} %)"]
        for d in drives:
            v = g[g["drive"] == d]["verdict"]
            c, nc, lost = ((v == k).sum() for k in ("converged", "not converged", "lost"))
            cells.append(f"{c} / {nc} / {lost}")
        for d in r2_drives:
            r2 = g[g["drive"] == d]["R2_error_pct"]
            cells.append(f"{r2.min():+.1f} … {r2.max():+.1f}" if len(r2) else "–")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


# ---------------------------------------------------------------------------------------------
# R2_hat against R1_hat near zero stator frequency

#: R1_hat / R1 of the R1-sensitivity runs (fixed: no standstill test, no online R1 law).
R1_RATIOS = (0.999, 1.0, 1.001)
#: Its machines and stator frequencies (Hz): the paper's, the small high-R1 one and the large
#: low-slip one.
R1_MACHINES = ("paper-table-iv", "aalto-2.2kw", "krause-500hp")
R1_F_S_HZ = (0.0, 0.25, 0.5, 1.0, 2.0)


def _r1_drive(ratio: float) -> str:
    return f"injection-robust-afo R1x{ratio:g}"


# ``injection-robust`` on the observer with R1_hat held at a given share of R1 (the drives of
# :func:`r1_sensitivity`; judged as ``injection-robust``: machines.tracks_r2)
for _r in R1_RATIOS:
    envelope.DRIVE_ALIASES[_r1_drive(_r)] = (
        "injection-robust",
        ('control.speed_feedback="afo"', f"estimator.R1_ratio={_r}", "mras.R1_standstill=false"),
    )


def r1_sensitivity(machines=R1_MACHINES, frequencies=R1_F_S_HZ, ratios=R1_RATIOS):
    """R2_hat at the end against R1_hat near zero stator frequency.

    ``injection-robust`` on the adaptive observer (which keeps control there: the study's
    other table), regenerating the rated torque at the stator frequencies ``frequencies``
    from R2_hat(0) = R2, with R1_hat held at ``ratios`` times R1 (no standstill test, no
    online R1 law). At zero stator frequency the fundamental-frequency signals cannot tell
    R1 from R2 (Holtz, Proc. IEEE 90(8), 2002), and the injection does not make up for it
    here: what these runs measure is how far R2_hat follows an R1_hat error of 0.1 %, the
    accuracy no identification of R1 holds through a run (the rotor and stator heat).

    Returns
    -------
    DataFrame
        The machine envelope's columns and ``f_s_target_Hz``, ``R1_ratio``; one row per run.
    """
    scs, table = scenarios(machines, frequencies, (1.0,), drives=[_r1_drive(r) for r in ratios])
    df = envelope.measure(scs, table)
    df["R1_ratio"] = df["drive"].map({_r1_drive(r): r for r in ratios})
    return df


def r1_sensitivity_lines(df: pd.DataFrame) -> list[str]:
    """The R1-sensitivity table: per machine and stator frequency, R2_hat's error at the end
    for each R1_hat, and the most an R1_hat error of one step (0.1 %) moved it from its end
    with R1_hat = R1, percentage points of R2 (a lost run is marked and left out of it)."""
    ratios = sorted(df["R1_ratio"].unique())
    step = 100 * min(abs(r - 1.0) for r in ratios if r != 1.0)
    head = "| machine | f_s, Hz | " + " | ".join(f"R̂2 error, R̂1 = {r:g} R1, %" for r in ratios)
    lines = [
        head + f" | R̂2 moved by a {step:g} % R̂1 error, % of R2 |",
        "|---|---|" + "---|" * (len(ratios) + 1),
    ]
    for (m, f), g in df.groupby(["machine", "f_s_target_Hz"], sort=False):
        g = g.set_index("R1_ratio")
        cells = [m, f"{f:+.2f}"]
        for r in ratios:
            e = float(g.loc[r, "R2_error_pct"])
            cells.append(f"{e:+.2f}" + (" (lost)" if g.loc[r, "verdict"] == "lost" else ""))
        kept = g[g["verdict"] != "lost"]["R2_error_pct"]
        moved = (kept - kept.get(1.0, float("nan"))).abs().max()
        cells.append(f"{moved:.1f}" if math.isfinite(moved) else "–")
        lines.append("| " + " | ".join(cells) + " |")
    return lines
