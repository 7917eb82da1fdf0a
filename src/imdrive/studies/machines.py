"""The drive over the machine library: every published machine, in per-unit of itself.

For each machine of ``config/data/machines.toml`` and each of two drives -- ``sensorless``
(Schauder's MRAS, no R2 tracking; its voltage-feedback field weakening on by default from
0.84-0.88 of the rated speed, :data:`DRIVE_OVERRIDES`) and ``injection-robust`` (the recommended
R2-tracking preset) -- and, for comparison, ``sensorless-afo`` (``sensorless`` with the adaptive
full-order observer's speed, :data:`DRIVE_ALIASES`; not part of the goal), a grid in per-unit
of the machine: speed reference as a fraction of its
rated speed, load torque as a fraction of its rated torque (negative: regenerating), and the
controller's starting ``R2_hat(0)/R2``. Only ``[machine]`` and the operating point change: every
other setting the presets leave derived or state in per-unit (config/perunit.py), which is what
this study checks.

Times follow the machine too (:func:`timeline`): the speed reference ramps from 0 once the
rotor is magnetised (:func:`ramp_start_s`: four rotor time constants, at least 0.5 s, the
presets' start; the compensator and the injection start as much later) over
``max(1 s, 2 tau_m)`` (``tau_m = J w_rated / T_rated``, the time the rated torque takes to
reach the rated speed, so the ramp needs at most half the rated torque), the load steps 0.5 s
after the ramp (a drive that runs the standstill R1 test holds both until the test has its
window, and its run ends that much later: :func:`standstill_wait_s`), and the run ends
``T_END_S - 2 s`` later, stretched by
``T2 / T2_TableIV`` for a machine whose rotor is slower than Table IV's (the R2 detection's
injection frequency, hence its decisions, scale with ``1/T2``). Its verdict (:func:`verdict`):

* ``lost``: it lost control (the speed left its reference by the loss-of-control bound for a
  second) or diverged;
* ``converged``: ``sensorless``: the steady speed error equals the detuning law's
  ``slip (R2_hat/R2 - 1)`` (:func:`imdrive.analysis.detuning_speed_error_rpm`) at the flux
  the field weakening settles at (:func:`detuning_law_rpm`) within the tolerance;
  a drive that tracks R2 (:func:`tracks_r2`: its compensator or its estimator's own R2
  law on; ``injection-robust`` and the drives made from it): R2_hat within 2 %
  of R2 at the end and over the final window (``R2_error_window_pct``) and the speed error
  within the tolerance.
  The tolerance is 1 rpm or 0.1 % of the rated speed, whichever is larger;
* ``not converged``: stable, but outside those bounds at the end.

``python -m imdrive.studies.machines OUT_CSV`` runs the grid (1008 drives) and writes
the runs; ``python -m imdrive.studies.machines --markdown CSV`` prints the table of
docs/machine-envelope.md, which a test re-renders from the stored CSV; ``--drive NAME``
measures one drive's rows of that CSV again (:func:`update_drive`). :func:`ramp_diagnosis`
measures why the large machines lose control at rated speed (a table of the same page,
``python -m imdrive.studies.doctables --run machine-ramp-diagnosis``).
"""

from __future__ import annotations

import functools
import math
import sys
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from imdrive.analysis.drive_steady_state import (  # noqa: F401  (re-exported: their old home)
    detuning_law_rpm,
    law_flux_Wb,
    stator_frequency_Hz,
)
from imdrive.config.machine import machine_presets, rated_point
from imdrive.config.perunit import SPEED_TOLERANCE_MIN_RPM, SPEED_TOLERANCE_PU
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning
from imdrive.run.batch import simulate_batch
from imdrive.run.status import r2_worst_pct

#: The drives of the grid: the goal's two presets, and for comparison ``sensorless`` on the
#: adaptive observer and the recommended drive on the MRAS (its estimator until 2026-11-30).
DRIVES = ("sensorless", "injection-robust", "sensorless-afo", "injection-robust-mras")
#: The drives the goal (at least Table IV's share converged on every machine) is read over.
GOAL_DRIVES = ("sensorless", "injection-robust")
#: A drive that is a preset with overrides: ``sensorless`` with the adaptive full-order
#: observer's speed (``control.speed_feedback = "afo"``, docs/estimators.md) instead of the
#: MRAS's, to show which of the misses are the MRAS's.
DRIVE_ALIASES: dict[str, tuple[str, tuple[str, ...]]] = {
    "sensorless-afo": ("sensorless", ('control.speed_feedback="afo"',)),
    # the recommended drive on the MRAS, its estimator until the measurements of
    # docs/machine-envelope.md chose the observer (2026-11-30): the grid's fourth drive
    "injection-robust-mras": ("injection-robust", ('control.speed_feedback="mras"',)),
    # the observer's drive by its old name (the preset itself since 2026-11-30)
    "injection-robust-afo": ("injection-robust", ('control.speed_feedback="afo"',)),
}
#: What the grid adds to a drive's preset, the same on every machine: nothing now. The field
#: weakening it added to ``sensorless`` (at rated speed and torque the rated flux needs 1.01-1.06
#: of the inverter's sqrt 2 x V_rated DC link on the large machines) comes by default wherever
#: the speed reference reaches that voltage
#: (:func:`imdrive.config.field_weakening.field_weakening_needed`), as a user who replaces the
#: preset's ``[machine]`` gets it.
DRIVE_OVERRIDES: dict[str, tuple[str, ...]] = {}
SPEEDS_PU = (0.05, 0.1, 0.5, 1.0)
LOADS_PU = (-1.0, 0.0, 1.0)
R2_RATIOS = (0.7, 0.8, 1.2, 1.3)
T_END_S = 14.5
R2_BAND_PCT = 2.0


def tolerance_rpm(rated_speed_rpm: float) -> float:
    """The speed tolerance: 1 rpm or 0.1 % of the rated speed, whichever is larger, rpm (the
    runs' status uses the same, :func:`imdrive.config.perunit.speed_tolerance_rpm`)."""
    return max(SPEED_TOLERANCE_MIN_RPM, SPEED_TOLERANCE_PU * rated_speed_rpm)


#: Table IV's rotor time constant L2/R2, s (the time scale the presets' timings were set for)
T2_TABLE_IV = 0.0870
#: The ramp starts once the rotor is magnetised (``injection-robust``'s standstill R1 window
#: opens about 3.7 rotor time constants into the magnetisation and the start waits for the
#: rest of it, :func:`standstill_wait_s`): after this many rotor time constants ...
RAMP_START_T2 = 4.0
#: ... and not before this (the presets' own start), s
RAMP_START_MIN_S = 0.5


#: The one-level standstill R1 test holds the start (kernels/estimators/mras_standstill.py) until
#: its window has half a T2_hat(0), the window opening up to a block (a quarter T2_hat(0)) after
#: the grid's ramp start (measured: the start moved 0.11 s on Krause 50 hp and 0.56 s on Krause
#: 2250 hp from 0.8 R2). The drive holds its whole duty cycle, the load step too, that long
#: (kernels/stages.py, ``t_hold``), not the run's end: a drive that runs the test ends this many
#: T2_hat(0) later, so its final window still follows the load step as long
STANDSTILL_WAIT_T2_HAT = 0.75


def standstill_wait_s(sc, R2_ratio: float) -> float:
    """How much later a run of drive ``sc`` from ``R2_hat(0) = R2_ratio R2`` ends than
    :func:`timeline` says, s: :data:`STANDSTILL_WAIT_T2_HAT` times ``T2_hat(0) = T2 /
    R2_ratio`` where the drive identifies R1 at standstill (``mras.R1_standstill``), else 0.
    (Until the drive held its load with its speed reference, the grid stepped the load this
    much later too: the rated regenerating step on Krause 2250 hp had come before the ramp's
    end and lost control for a second.)"""
    if not sc.mras.R1_standstill:
        return 0.0
    return STANDSTILL_WAIT_T2_HAT * rotor_time_constant_s(sc.machine) / R2_ratio


def rotor_time_constant_s(machine) -> float:
    """The machine's rotor time constant ``L2 / R2``, s."""
    return (machine.Ll2_H + machine.M_H) / machine.R2_ohm


def ramp_start_s(machine) -> float:
    """When the grid's speed ramp starts on ``machine``, s: ``RAMP_START_T2`` rotor time
    constants (the flux is then within 2 % of its reference), at least ``RAMP_START_MIN_S``
    (0.5 s on Table IV, Krause 3 hp and the Aalto machine; 0.62 s on Krause 50 hp; 3.13,
    6.40 and 3.43 s on Krause 500 hp, 2250 hp and the 3.3 kV machine)."""
    return max(RAMP_START_MIN_S, RAMP_START_T2 * rotor_time_constant_s(machine))


def timeline(machine) -> tuple[float, float, float]:
    """``(ramp_s, load_at_s, t_end_s)`` of a run on ``machine`` (module docstring)."""
    rp = rated_point(machine)
    w_rated = rp.speed_rpm * math.pi / 30.0
    tau_m = machine.J_kgm2 * w_rated / rp.torque_Nm
    ramp = max(1.0, 2.0 * tau_m)
    load_at = ramp_start_s(machine) + ramp + 0.5
    T2 = rotor_time_constant_s(machine)
    return ramp, load_at, load_at + (T_END_S - 2.0) * max(1.0, T2 / T2_TABLE_IV)


def _later_start(base, delay: float) -> list[str]:
    """Overrides moving R2 tracking's start (the compensator's, and its injection's with it)
    by ``delay`` s (the ramp starts that much later than in the preset), none when ``delay``
    is 0."""
    if delay <= 0.0 or not base.compensator.enabled:
        return []
    return [f"compensator.t_on_s={base.compensator.t_on_s + delay}"]


def scenarios(machines=None, drives=DRIVES, speeds=SPEEDS_PU, loads=LOADS_PU, ratios=R2_RATIOS):
    """The grid's scenarios and a row describing each.

    Parameters
    ----------
    machines : sequence of str, optional
        Machine presets (default: the whole library).
    drives : sequence of str
        Scenario presets.
    speeds, loads : sequence of float
        Speed reference and load torque in per-unit of the machine's rated speed and torque.
    ratios : sequence of float
        ``R2_hat(0)/R2``.

    Returns
    -------
    list of Scenario
    pandas.DataFrame
        ``machine, drive, speed_pu, load_pu, R2_ratio, speed_rpm, load_Nm, rated_speed_rpm``.
    """
    rows, out = [], []
    for m in machines or machine_presets():
        for drive in drives:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConfigWarning)
                preset, alias = DRIVE_ALIASES.get(drive, (drive, ()))
                base = Scenario.read(
                    preset, [f'machine.preset="{m}"', *alias, *DRIVE_OVERRIDES.get(drive, ())]
                )
            rp = rated_point(base.machine)
            ramp, load_at, t_end = timeline(base.machine)
            start = ramp_start_s(base.machine)
            later = _later_start(base, start - RAMP_START_MIN_S)
            for s in speeds:
                for load in loads:
                    for r in ratios:
                        n, T = s * rp.speed_rpm, load * rp.torque_Nm
                        wait = standstill_wait_s(base, r)
                        ov = [
                            f"control.speed_ref_rpm={{initial=0, changes=[{{at={start}, "
                            f"to={n}, over={ramp}}}]}}",
                            f"load.torque_Nm={{initial=0, changes=[{{at={load_at}, to={T}}}]}}",
                            f"simulation.t_end_s={t_end + wait}",
                            f"estimator.R2_ohm={r * base.machine.R2_ohm}",
                        ]
                        if base.estimator.R2_ratio is not None:
                            ov[-1] = f"estimator.R2_ratio={r}"
                        out.append(base.with_overrides(later + ov))
                        rows.append(
                            dict(
                                machine=m,
                                drive=drive,
                                speed_pu=s,
                                load_pu=load,
                                R2_ratio=r,
                                speed_rpm=n,
                                load_Nm=T,
                                rated_speed_rpm=rp.speed_rpm,
                            )
                        )
    return out, pd.DataFrame(rows)


@functools.cache
def _named_tracks_r2(drive: str) -> bool:
    preset, alias = DRIVE_ALIASES.get(drive, (drive, ()))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        return tracks_r2(Scenario.read(preset, list(alias)))


def tracks_r2(drive) -> bool:
    """Whether ``drive`` (a Scenario, or a drive's name: a preset or :data:`DRIVE_ALIASES`)
    tracks R2, by its compensator or its estimator's own R2 law, so that its runs are judged
    by their R2_hat error, not by the detuning law of a drive that holds R2_hat. (Until
    2026-11-30 by the name alone: ``injection-robust`` or made from it, so that an alias of
    ``sensorless`` with ``estimator.R2_adaptation = "afo"`` was judged by the detuning law.)"""
    if isinstance(drive, str):
        return _named_tracks_r2(drive)
    return drive.compensator.enabled or drive.estimator.R2_adaptation != "compensator"


def verdict(row) -> str:
    """``lost``, ``converged`` or ``not converged`` for one run (module docstring)."""
    if row["status"] != 0 or row["lost_control"]:
        return "lost"
    tol = tolerance_rpm(row["rated_speed_rpm"])
    tracks = row.get("tracks_r2")  # a stored CSV has no such column: by the drive's name
    if tracks_r2(row["drive"]) if tracks is None or pd.isna(tracks) else tracks:
        # older CSVs have no window column: the end alone
        r2 = r2_worst_pct(row["R2_error_pct"], row.get("R2_error_window_pct", math.nan))
        ok = r2 <= R2_BAND_PCT and abs(row["speed_error_rpm"]) <= tol
    else:
        ok = abs(row["speed_error_rpm"] - row["detuning_law_rpm"]) <= tol
    return "converged" if ok else "not converged"


def run(machines=None, **grid) -> pd.DataFrame:
    """Run the grid and return one row per drive with its metrics and verdict.

    Parameters
    ----------
    machines : sequence of str, optional
        Machine presets (default: the whole library).
    **grid
        ``drives``, ``speeds``, ``loads``, ``ratios`` of :func:`scenarios`.

    Returns
    -------
    pandas.DataFrame
        The grid's columns, the batch metrics, ``detuning_law_rpm`` (:func:`detuning_law_rpm`),
        ``law_flux_pu`` (the flux it is computed at, per-unit of the rated flux,
        :func:`law_flux_Wb`), ``f_s_Hz`` and ``f_s_R2_Hz`` (the steady state's stator
        frequency with ``R2_hat(0)`` and with ``R2_hat = R2``, :func:`stator_frequency_Hz`)
        and ``verdict``.
    """
    return measure(*scenarios(machines, **grid))


def measure(scs, table: pd.DataFrame) -> pd.DataFrame:
    """Simulate the scenarios ``scs`` of :func:`scenarios` and add to its ``table`` the
    metrics, the detuning law, the stator frequencies and the verdicts (:func:`run`)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        res = simulate_batch(scs, errors="record")
    m = res.metrics.drop(columns=["drive"])
    table = pd.concat([table, m], axis=1)
    pairs = list(zip(scs, table.itertuples(), strict=True))
    law, flux = [], []
    table["tracks_r2"] = [tracks_r2(sc) for sc in scs]
    for sc, r in pairs:  # the detuning law and its flux, for a drive that holds R2_hat
        held = not tracks_r2(sc)
        args = (sc, r.speed_rpm, r.load_Nm, r.R2_ratio)
        law.append(detuning_law_rpm(*args) if held else math.nan)
        flux.append(law_flux_Wb(*args) / sc.machine.rated_flux_Wb if held else math.nan)
    table["detuning_law_rpm"], table["law_flux_pu"] = law, flux
    for col, ratio in (("f_s_Hz", None), ("f_s_R2_Hz", 1.0)):
        table[col] = [
            stator_frequency_Hz(sc, r.speed_rpm, r.load_Nm, ratio or r.R2_ratio) for sc, r in pairs
        ]
    table["verdict"] = [verdict(r) for _, r in table.iterrows()]
    return table


def stator_frequency_summary(table: pd.DataFrame) -> str:
    """One sentence on where the runs outside the converged column are: the highest stator
    frequency among them (the lower of ``f_s_Hz`` and ``f_s_R2_Hz``: the drive starts at the
    one and, tracking R2, moves to the other), and how many runs at or below it converged.
    Empty for a CSV without the columns (before 2026-11-24) or with every run converged."""
    if "f_s_Hz" not in table or "f_s_R2_Hz" not in table:
        return ""
    f_low = np.minimum(table["f_s_Hz"], table["f_s_R2_Hz"])
    bad = table["verdict"] != "converged"
    if not bad.any():
        return ""
    top = float(f_low[bad].max())
    near = f_low <= top
    ok = int((near & ~bad).sum())
    drives = " and ".join(f"`{d}`" for d in dict.fromkeys(table["drive"]))
    return (
        f"\nThe {int(bad.sum())} runs of {drives} outside the converged column all run at a stator "
        f"frequency of at most {top:+.2f} Hz (steady state, the lower of R̂2(0)'s and R2's, "
        f"`f_s_Hz` and `f_s_R2_Hz` in the CSV; lowest {float(f_low[bad].min()):+.2f} Hz); "
        f"{ok} of the {int(near.sum())} runs at or below that frequency converged, and "
        f"every run above it did ({int((~near).sum())}).\n"
    )


def markdown(table: pd.DataFrame) -> str:
    """The per-machine table: runs converged / not converged / lost for each drive of the
    table, and whether each machine's share converged is at least Table IV's for the drives
    of :data:`GOAL_DRIVES` (the goal); under it :func:`stator_frequency_summary` of those.

    Parameters
    ----------
    table : pandas.DataFrame
        As :func:`run` returns it (or read back from its CSV).

    Returns
    -------
    str
        A Markdown table, one row per machine, one column group per drive.
    """
    drives = [d for d in DRIVES if d in set(table["drive"])]
    goal = [d for d in GOAL_DRIVES if d in drives]
    lines = [
        "| machine | "
        + " | ".join(f"{d}: converged / not / lost" for d in drives)
        + f" | at least Table IV's share ({', '.join(goal)}) |",
        "|---|" + "---|" * (len(drives) + 1),
    ]

    def share(g, d):
        v = g[g["drive"] == d]["verdict"]
        return (v == "converged").mean() if len(v) else float("nan")

    ref = table[table["machine"] == "paper-table-iv"]
    for m, g in table.groupby("machine", sort=False):
        cells = []
        for d in drives:
            v = g[g["drive"] == d]["verdict"]
            n = len(v)
            c, nc, lost = ((v == k).sum() for k in ("converged", "not converged", "lost"))
            cells.append(f"{c} / {nc} / {lost} of {n} ({100 * c / n:.0f} %)" if n else "–")
        below = [d for d in goal if len(ref) and share(g, d) < share(ref, d)]
        cells.append("**no**: " + ", ".join(below) if below else ("yes" if len(ref) else "–"))
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n" + stator_frequency_summary(table[table["drive"].isin(goal)])


#: The runs of :func:`ramp_diagnosis`: (machine, speed feedback, ramp stretch, ramp start in s
#: or None for the grid's, ``mras.acceleration_tracking`` or None for its default)
DIAGNOSIS_RUNS = (
    ("paper-table-iv", "mras", 1.0, None, None),
    ("krause-500hp", "mras", 1.0, None, False),
    ("krause-2250hp", "mras", 1.0, None, False),
    ("geyer-3.3kv", "mras", 1.0, None, False),
    ("krause-500hp", "measured", 1.0, None, False),
    ("krause-500hp", "mras", 4.0, None, False),
    ("krause-500hp", "mras", 1.0, None, None),
    ("krause-2250hp", "mras", 1.0, None, None),
    ("geyer-3.3kv", "mras", 1.0, None, None),
    ("krause-2250hp", "mras", 1.0, 0.5, None),  # type 2, before the rotor is magnetised
)


def _diagnosis_scenario(name, feedback, stretch, start, tracking):
    """The scenario of one :func:`ramp_diagnosis` run and its rated point, ramp and start."""
    scs, _ = scenarios([name], drives=["sensorless"], speeds=[1.0], loads=[0.0], ratios=[1.0])
    base = scs[0]
    rp = rated_point(base.machine)
    ramp = stretch * timeline(base.machine)[0]
    start_given = start
    start = ramp_start_s(base.machine) if start is None else start
    ov = [  # the MRAS's ramp lag alone: the field weakening would hide the voltage limit
        "control.field_weakening=false",
        f'control.speed_feedback="{feedback}"',
        f"control.speed_ref_rpm={{initial=0, changes=[{{at={start}, "
        f"to={rp.speed_rpm}, over={ramp}}}]}}",
        f"simulation.t_end_s={start + ramp + 3.0}",
    ]
    if tracking is not None:
        ov.append(f"mras.acceleration_tracking={str(tracking).lower()}")
    if start_given is not None:  # that start, not the drive's premagnetisation (3 T2_hat)
        ov.append("control.premagnetise_T2=0")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        return base.with_overrides(ov), rp, ramp, start


def ramp_diagnosis(runs=DIAGNOSIS_RUNS) -> pd.DataFrame:
    """Why the sensorless drive lost control at rated speed on the large machines, and what
    the type-2 adaptation of the MRAS changes (docs/machine-envelope.md).

    The grid's run at rated speed, no load, ``R2_hat(0) = R2`` (no detuning), up to 3 s after
    the ramp, with the MRAS (type 1 or type 2, ``mras.acceleration_tracking``) or the
    measured speed as feedback, the ramp as in the grid or stretched, starting as in the grid
    (:func:`ramp_start_s`) or at a given time (the drive's premagnetisation off: the time is
    the start).

    Parameters
    ----------
    runs : sequence of tuple
        ``(machine, control.speed_feedback, ramp stretch, ramp start in s or None,
        mras.acceleration_tracking or None)``; the last may be left out (None).

    Returns
    -------
    pandas.DataFrame
        Per run: ``machine, feedback, adaptation`` (``type 1`` or ``type 2``, as the MRAS
        ran), ``ramp_s, start_s``; ``rated_slip_rpm``; ``corner_rpm``, the rotor's corner
        frequency ``1/T2`` as a mechanical speed (the MRAS's linear range);
        ``estimate_lag_rpm``, the median of speed minus MRAS estimate while the reference is
        between 5 and 50 % of rated (also with the measured speed as feedback, where the
        MRAS runs beside), ``lag_pu_slip`` and ``lag_pu_corner``, over the rated slip and
        over ``corner_rpm``; ``max_flux_pu``, the plant's largest ``|psi_r|`` over the rated
        flux; ``voltage_limit_at_pu``, the speed reference (per-unit of rated) when the
        voltage reference first reaches 99 % of the inverter's limit (NaN: never); ``lost``.
    """
    from imdrive.config.estimators import mras_type2
    from imdrive.config.perunit import resolve
    from imdrive.run.simulate import simulate

    rows = []
    for run_ in runs:
        name, feedback, stretch, start, tracking = (*run_, None)[:5]
        sc, rp, ramp, start = _diagnosis_scenario(name, feedback, stretch, start, tracking)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConfigWarning)
            res = simulate(sc)
        df = res.to_pandas()
        D = resolve(sc)
        T2_hat = (D.Ll2_hat + D.M_hat) / D.R2_hat
        ref = df["speed_ref_rpm"] / rp.speed_rpm
        during = (ref > 0.05) & (ref < 0.5)
        lag = float((df["speed_rpm"] - df["speed_est_rpm"])[during].median())
        at_limit = np.hypot(df["v_ref_alpha_V"], df["v_ref_beta_V"]) >= 0.99 * D.v_max_V
        slip = rp.synchronous_speed_rpm - rp.speed_rpm
        corner = 30.0 / (math.pi * T2_hat * sc.machine.pole_pairs)
        rows.append(
            dict(
                machine=name,
                feedback=feedback,
                adaptation="type 2" if mras_type2(sc, sc.mras, T2_hat) else "type 1",
                ramp_s=ramp,
                start_s=start,
                rated_slip_rpm=slip,
                corner_rpm=corner,
                estimate_lag_rpm=lag,
                lag_pu_slip=lag / slip,
                lag_pu_corner=lag / corner,
                max_flux_pu=float(df["flux_Wb"].max() / D.psi_rated),
                voltage_limit_at_pu=float(ref[at_limit].iloc[0]) if at_limit.any() else math.nan,
                lost=bool(res.summary()["lost_control"]),
            )
        )
    return pd.DataFrame(rows)


def diagnosis_markdown(df: pd.DataFrame) -> list[str]:
    """The table of :func:`ramp_diagnosis` for docs/machine-envelope.md (Markdown lines)."""

    def num(v, fmt):
        return "–" if pd.isna(v) else format(v, fmt)

    lines = [
        "| machine | feedback | MRAS | ramp from, s | ramp, s | rated slip, rpm | 1/T2, rpm "
        "| estimate lag, rpm (× slip, × 1/T2) | largest ψr / rated "
        "| voltage limit reached at, × rated speed | lost control |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in df.itertuples():
        lag = f"{r.estimate_lag_rpm:.2f} ({r.lag_pu_slip:.2f}, {r.lag_pu_corner:.2f})"
        lines.append(
            f"| {r.machine} | {r.feedback} | {r.adaptation} | {r.start_s:.2f} | {r.ramp_s:.2f} "
            f"| {r.rated_slip_rpm:.1f} | {r.corner_rpm:.1f} | {lag} "
            f"| {r.max_flux_pu:.2f} | {num(r.voltage_limit_at_pu, '.2f')} "
            f"| {'yes' if r.lost else 'no'} |"
        )
    return lines


PAGE = Path(__file__).resolve().parents[3] / "docs" / "machine-envelope.md"
CSV = PAGE.parent / "data" / "machine_envelope.csv"
_BEGIN = (
    "<!-- table: python -m imdrive.studies.machines --markdown docs/data/machine_envelope.csv -->"
)
_END = "<!-- end of table -->"


def page_with_table(text: str, table_md: str) -> str:
    """``text`` (docs/machine-envelope.md) with the generated table between its markers."""
    a = text.index(_BEGIN) + len(_BEGIN)
    b = text.index(_END)
    return text[:a] + "\n" + table_md + text[b:]


def update_drive(drive: str) -> pd.DataFrame:
    """Measure ``drive``'s rows of the docs' CSV again or for the first time (the others kept,
    in :data:`DRIVES`' order), write it, refresh the page's table; return the new rows."""
    old = pd.read_csv(CSV)
    new = measure(*scenarios(drives=(drive,)))
    rows = []
    drives = [d for d in DRIVES if d in set(old["drive"]) | {drive}]  # a new one: its place
    for m in old["machine"].unique():
        for d in drives:
            src = new if d == drive else old
            rows.append(src[(src["machine"] == m) & (src["drive"] == d)])
    pd.concat(rows, ignore_index=True)[old.columns].to_csv(CSV, index=False, float_format="%.9g")
    PAGE.write_text(page_with_table(PAGE.read_text(), markdown(pd.read_csv(CSV))))
    return new


def main(argv=None) -> int:
    """``python -m imdrive.studies.machines OUT_CSV``, ``--markdown CSV`` or ``--drive NAME``
    (docstring, :func:`update_drive`)."""
    import argparse

    ap = argparse.ArgumentParser(
        prog="python -m imdrive.studies.machines", description=__doc__.splitlines()[0]
    )
    what = ap.add_mutually_exclusive_group(required=True)
    what.add_argument("out_csv", nargs="?", help="run the whole grid and write it here")
    what.add_argument("--markdown", metavar="CSV", help="print the table of a stored CSV")
    what.add_argument("--drive", metavar="NAME", help="measure one drive's rows of the docs' CSV")
    args = ap.parse_args(sys.argv[1:] if argv is None else argv)
    if args.markdown:
        sys.stdout.write(markdown(pd.read_csv(args.markdown)))
        return 0
    if args.drive:
        new = update_drive(args.drive)
        print(f"{len(new)} runs: {new['verdict'].value_counts().to_dict()}", file=sys.stderr)
        return 0
    table = run()
    out = Path(args.out_csv)
    out.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(out, index=False, float_format="%.9g")
    sys.stdout.write(markdown(table))
    if out.resolve() == CSV and PAGE.exists():  # the docs' own table: refresh it
        PAGE.write_text(page_with_table(PAGE.read_text(), markdown(pd.read_csv(CSV))))
    print(f"{len(table)} runs: {table['verdict'].value_counts().to_dict()}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
