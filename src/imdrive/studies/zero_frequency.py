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

from imdrive.config.machine import machine_preset, rated_point
from imdrive.config.scenario import Scenario
from imdrive.design.gains import torque_constant
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
#: The machine envelope's drives: ``injection-robust`` (on the adaptive full-order observer
#: since 2026-11-30, chosen by this study: the MRAS lost control in 15 of its 84 runs, the
#: observer in 1) and ``injection-robust-mras`` among them; the standstill R1 test serves
#: every estimator (kernels/r1_standstill.py), so the observer runs on an identified R1.
DRIVES = envelope.DRIVES
#: The drives whose R2_hat error at the end the table gives.
R2_DRIVES = ("injection-robust", "injection-robust-mras")


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
    :data:`R2_DRIVES` the R2_hat error at the end, lowest to highest; ``g`` of eq. (1)
    (:func:`predicted_sensitivity`), and below the table, per drive that tracks R2, how many
    of its runs outside "converged" are at points where eq. (1) puts a 1 % R1_hat error
    beyond the R2 tolerance (a run's status says "R2 weakly observable here",
    :func:`imdrive.run.status.r1_note`, from its own final operating point, or that it lost
    control near zero stator frequency, :func:`imdrive.run.status.low_frequency_note`)."""
    from imdrive.analysis.observability import R1_UNCERTAINTY
    from imdrive.run.status import R2_TOLERANCE, r1_note

    drives = list(dict.fromkeys(df["drive"]))
    r2_drives = [d for d in R2_DRIVES if d in drives]
    g_of = {
        key: predicted_sensitivity(*key)
        for key in dict.fromkeys(zip(df["machine"], df["f_s_target_Hz"], strict=True))
    }
    head = "| machine | f_s, Hz | speed, rpm (% rated) | g, eq. (1) | " + " | ".join(
        f"{d}: converged / not / lost" for d in drives
    )
    head += "".join(f" | {d}: R̂2 error at the end, %" for d in r2_drives)
    lines = [head + " |"]
    lines.append("|---|---|---|---|" + "---|" * (len(drives) + len(r2_drives)))
    for (m, f), g in df.groupby(["machine", "f_s_target_Hz"], sort=False):
        n, rated = float(g["speed_rpm"].iloc[0]), float(g["rated_speed_rpm"].iloc[0])
        gp = g_of[m, f]
        cells = [m, f"{f:+.2f}", f"{n:.1f} ({100 * n / rated:.1f} %)"]
        cells.append(f"{gp:.2f}" if math.isfinite(gp) else "∞")
        for d in drives:
            v = g[g["drive"] == d]["verdict"]
            c, nc, lost = ((v == k).sum() for k in ("converged", "not converged", "lost"))
            cells.append(f"{c} / {nc} / {lost}")
        for d in r2_drives:
            r2 = g[g["drive"] == d]["R2_error_pct"]
            cells.append(f"{r2.min():+.1f} … {r2.max():+.1f}" if len(r2) else "–")
        lines.append("| " + " | ".join(cells) + " |")
    # the run status's own criterion (r1_note), at the study's target point
    noted = [
        r1_note(g_of[k]) is not None for k in zip(df["machine"], df["f_s_target_Hz"], strict=True)
    ]
    df = df.assign(noted=noted)
    lines.append("")
    for d in r2_drives:  # (a drive that does not track R2 gives no such note)
        miss = df[(df["drive"] == d) & (df["verdict"] != "converged")]
        lines.append(
            f'- `{d}`: {int(miss["noted"].sum())} of its {len(miss)} runs outside "converged" '
            f"are at points where g × {100 * R1_UNCERTAINTY:g} % > {100 * R2_TOLERANCE:g} % "
            "(R2 weakly observable there: a run's status says so, or that it lost control "
            "near zero stator frequency)."
        )
    return lines


# ---------------------------------------------------------------------------------------------
# R2_hat against R1_hat near zero stator frequency

#: R1_hat / R1 of the R1-sensitivity runs (fixed: no standstill test; the MRAS's online R1 law
#: runs only motoring): 1 %, what a measured R1 is good to
#: (:data:`imdrive.analysis.observability.R1_UNCERTAINTY`).
R1_RATIOS = (0.99, 1.0, 1.01)
#: Its machines and stator frequencies (Hz): the paper's, the small high-R1 one and two large
#: slow-rotor ones.
R1_MACHINES = ("paper-table-iv", "aalto-2.2kw", "krause-50hp", "krause-500hp")
R1_F_S_HZ = (0.0, 0.25, 0.5, 1.0, 2.0)
#: Its speed estimators: the recommended drive's MRAS and the adaptive observer.
R1_ESTIMATORS = ("mras", "afo")


def _r1_drive(ratio: float, estimator: str = "afo") -> str:
    return f"injection-robust-{estimator} R1x{ratio:g}"


# ``injection-robust`` with R1_hat held at a given share of R1 (the drives of
# :func:`r1_sensitivity`; judged as ``injection-robust``: machines.tracks_r2)
for _e in R1_ESTIMATORS:
    for _r in R1_RATIOS:
        envelope.DRIVE_ALIASES[_r1_drive(_r, _e)] = (
            "injection-robust",
            (
                f'control.speed_feedback="{_e}"',
                f"estimator.R1_ratio={_r}",
                "mras.R1_standstill=false",
            ),
        )


def predicted_sensitivity(machine: str, f_s_Hz: float) -> float:
    """``g`` of :func:`imdrive.analysis.observability.r2_r1_sensitivity` at the study's
    operating point (the drive's flux reference, the load :data:`LOAD_PU`, the stator
    frequency ``f_s_Hz``) from the machine's circuit:
    ``|i_s| = hypot(psi/M, T / (1.5 p (M/L2) psi))``."""
    from imdrive.analysis.observability import r2_r1_sensitivity

    m = machine_preset(machine)
    rp = rated_point(m)
    psi = m.rated_flux_Wb  # the drive's flux reference
    L2 = m.M_H + m.Ll2_H
    iq = abs(LOAD_PU) * rp.torque_Nm / torque_constant(m.pole_pairs, m.M_H, L2, psi)
    i_s = math.hypot(psi / m.M_H, iq)
    return r2_r1_sensitivity(m.R1_ohm, m.M_H, L2, i_s, 2 * math.pi * f_s_Hz, psi)


def r1_sensitivity(
    machines=R1_MACHINES, frequencies=R1_F_S_HZ, ratios=R1_RATIOS, estimators=R1_ESTIMATORS
):
    """R2_hat at the end against R1_hat near zero stator frequency.

    ``injection-robust`` with each speed estimator of ``estimators``, regenerating the rated
    torque at the stator frequencies ``frequencies`` from R2_hat(0) = R2, with R1_hat held at
    ``ratios`` times R1 (no standstill test; the MRAS's online R1 law runs only motoring). At
    zero stator frequency the fundamental-frequency signals cannot tell R1 from R2 (Holtz,
    Proc. IEEE 90(8), 2002), and the injection does not make up for it: what these runs
    measure is how far R2_hat follows an R1_hat error of 1 %, against the voltage model's
    share ``g`` (:func:`predicted_sensitivity`).

    Returns
    -------
    DataFrame
        The machine envelope's columns and ``f_s_target_Hz``, ``R1_ratio``, ``estimator``,
        ``g_predicted``; one row per run.
    """
    drives = {_r1_drive(r, e): (r, e) for e in estimators for r in ratios}
    scs, table = scenarios(machines, frequencies, (1.0,), drives=list(drives))
    df = envelope.measure(scs, table)
    df["R1_ratio"] = df["drive"].map(lambda d: drives[d][0])
    df["estimator"] = df["drive"].map(lambda d: drives[d][1])
    df["g_predicted"] = [
        predicted_sensitivity(m, f) for m, f in zip(df["machine"], df["f_s_target_Hz"], strict=True)
    ]
    return df


def moved_pct(g: pd.DataFrame) -> float:
    """The most one step of R1_hat moved R2_hat's end from its end with R1_hat = R1, % of R2
    per % of R1 (``g`` holds one machine, frequency and estimator; lost runs left out)."""
    g = g.set_index("R1_ratio")
    kept = g[g["verdict"] != "lost"]["R2_error_pct"]
    base = kept.get(1.0, float("nan"))
    out = [abs(kept[r] - base) / abs(100 * (r - 1.0)) for r in kept.index if r != 1.0]
    return max(out) if out else float("nan")


def r1_sensitivity_lines(df: pd.DataFrame) -> list[str]:
    """The R1-sensitivity table: per machine and stator frequency, ``g`` of eq. (1) and, per
    estimator, R2_hat's error at the end for each R1_hat (a lost run marked) and how far one
    step of R1_hat moved it (:func:`moved_pct`)."""
    ratios = sorted(df["R1_ratio"].unique())
    ests = list(dict.fromkeys(df["estimator"]))
    errs = " / ".join(f"{r:g}" for r in ratios)
    head = "| machine | f_s, Hz | g, eq. (1) |"
    for e in ests:
        head += f" {e}: R̂2 error at R̂1 = {errs} R1, % | {e}: % of R2 per % of R1 |"
    lines = [head, "|---|---|---|" + "---|---|" * len(ests)]
    for (m, f), g in df.groupby(["machine", "f_s_target_Hz"], sort=False):
        gp = float(g["g_predicted"].iloc[0])
        cells = [m, f"{f:+.2f}", f"{gp:.2f}" if math.isfinite(gp) else "∞"]
        for e in ests:
            ge = g[g["estimator"] == e].set_index("R1_ratio")
            parts = []
            for r in ratios:
                err = f"{float(ge.loc[r, 'R2_error_pct']):+.1f}"
                parts.append(err + (" (lost)" if ge.loc[r, "verdict"] == "lost" else ""))
            moved = moved_pct(g[g["estimator"] == e])
            cells += [" / ".join(parts), f"{moved:.1f}" if math.isfinite(moved) else "–"]
        lines.append("| " + " | ".join(cells) + " |")
    return lines
