"""The recommended R2-tracking drive on a realistic drive, down to 0.2 of the rated speed.

``docs/envelope.md``'s whole-rating envelope runs ``injection-robust`` on an average inverter
and a linear machine, and the realistic envelope of docs/paper-reproduction.md runs the
paper's injection variant (its fuzzy table) from 0.3 of the rated speed up. Here the
recommended preset itself runs on the realistic presets' drive (:data:`REALISTIC`: the
switching bridge with dead time and device drop, one period's delay, the current sensors'
gain mismatch, offsets, noise and 12-bit ADC, the saturating machine, and the controller a
commissioning gives, ``controller_model.ideal``), at speeds and loads in per-unit of three
machines (:data:`MACHINES`), from R̂2(0) = 0.8 and 1.2 R2, on the preset's own timeline
(the sweep's ``speed_pu`` and ``load_pu`` axes change only the profiles' final values). Each
run is judged by its own status (:mod:`imdrive.run.status`): ``ok`` is R̂2 within 2 % at the
end and over the final window, and the speed within the drive's tolerance.

``python -m imdrive.studies.doctables --run realistic-envelope`` measures it again (72 runs on
each of the sensors' noise seeds :data:`SEEDS`, 288 in all, about a minute once compiled) and
rewrites its table in docs/envelope.md.
"""

from __future__ import annotations

import warnings

import pandas as pd

from imdrive.config.rated import rated_point
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning
from imdrive.run.batch import simulate_batch
from imdrive.studies.doctable import DocTable, register
from imdrive.studies.realistic import NON_IDEALITIES

#: The drive the grid runs.
PRESET = "injection-robust"
#: The realistic presets' drive (``injection-fig5-realistic``, ``sensorless-realistic``: each
#: value is theirs, which a test checks), applied to :data:`PRESET`: the non-idealities of
#: :mod:`imdrive.studies.realistic`, with the commissioned controller's inverter-error table
#: instead of the uncommissioned dead-time feed-forward.
REALISTIC = (
    'inverter.model="switching"',
    "inverter.dead_time_s=2e-6",
    "inverter.device_drop_V=1.0",
    *NON_IDEALITIES["delay"],
    # the ADC's range is the machine's (derived), not Table IV's 50 A
    *(o for o in NON_IDEALITIES["sensors"] if not o.startswith("sensor.adc_range_A")),
    *NON_IDEALITIES["saturation"],
    "controller_model.ideal=true",
)
#: The paper's machine, the Aalto laboratory machine and Krause's 3 hp: rated slip 4.4-5.3 %,
#: 2.2-3 kW, the power the realistic presets' bridge (10 kHz, 2 us) is typical of.
MACHINES = ("paper-table-iv", "aalto-2.2kw", "krause-3hp")
#: Speed reference, per-unit of the rated speed: the low-speed cells the whole-rating grid of
#: the realistic envelope leaves out (0.2, 0.3) and two of its own.
SPEEDS_PU = (0.2, 0.3, 0.5, 1.0)
#: Load, per-unit of the rated torque (negative: regenerating).
LOADS_PU = (-1.0, 0.0, 1.0)
#: R̂2(0)/R2.
R2_RATIOS = (0.8, 1.2)
#: Seeds of the current sensors' noise (``sensor.seed``; the realistic presets' is 1). One seed
#: decided two to four of the 72 cells either way (measured 2026-11-30: 64, 66, 70 and 69
#: ``ok`` on seeds 1-4; 71, 72, 71 and 71 once the detection removed the sensors'
#: offsets), so the table gives seed 1's count and the range over these.
SEEDS = (1, 2, 3, 4)
#: The grid of the ``envelope-realistic`` sweep (docs/paper-reproduction.md, the paper's
#: injection variant on Table IV: 516-1721 rpm, -12.4 ... +12.4 N m) in per-unit of each
#: machine, on the presets' noise seed: the recommended drive where the paper's variant was
#: measured (:func:`measure_sweep_grid`; 225 runs, about 30 s once compiled).
SWEEP_GRID = {
    "speeds": (0.3, 0.5, 0.7, 0.85, 1.0),
    "loads": (-1.0, -0.5, 0.0, 0.5, 1.0),
    "ratios": (0.8, 1.0, 1.2),
    "seeds": (1,),
}


def _profile(key: str, at: float, value: float, over: float | None = None) -> str:
    ramp = f", over={over}" if over is not None else ""
    return f"{key}={{initial=0, changes=[{{at={at}, to={value:.6g}{ramp}}}]}}"


def scenarios(machines=MACHINES, speeds=SPEEDS_PU, loads=LOADS_PU, ratios=R2_RATIOS, seeds=SEEDS):
    """The grid's scenarios and a row describing each (``machine, speed_pu, load_pu,
    R2_ratio, seed``)."""
    rows, scs = [], []
    for m, seed in ((m, seed) for seed in seeds for m in machines):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConfigWarning)
            base = Scenario.read(
                PRESET, [f'machine.preset="{m}"', *REALISTIC, f"sensor.seed={seed}"]
            )
        # the preset's ramp (its last two breakpoints) and load step, to other final values
        (t0, _), (t1, _) = base.control.speed_ref_pu.points[-2:]
        t_load = base.load.torque_pu.points[-1][0]
        for s in speeds:
            for load in loads:
                for r in ratios:
                    ov = [
                        _profile("control.speed_ref_pu", t0, s, t1 - t0),
                        _profile("load.torque_pu", t_load, load),
                        f"estimator.R2_ratio={r}",
                    ]
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", ConfigWarning)
                        scs.append(base.with_overrides(ov))
                    rows.append((m, s, load, r, seed))
    cols = ["machine", "speed_pu", "load_pu", "R2_ratio", "seed"]
    return scs, pd.DataFrame(rows, columns=cols)


def measure(**grid) -> pd.DataFrame:
    """Run the grid: its rows with the R̂2 error at the end and over the final window, %, the
    speed error, rpm, and its tolerance, whether control was lost and the run's verdict."""
    scs, table = scenarios(**grid)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        res = simulate_batch(scs, errors="record")
    m = res.metrics
    cols = (
        "R2_error_pct",
        "R2_error_window_pct",
        "speed_error_rpm",
        "speed_tolerance_rpm",
        "lost_control",
        "verdict",
    )
    for col in cols:
        table[col] = m[col].to_numpy()
    table["rated_speed_rpm"] = [rated_point(sc.machine).speed_rpm for sc in scs]
    return table


def measure_sweep_grid(machines=MACHINES) -> pd.DataFrame:
    """:func:`measure` on :data:`SWEEP_GRID`."""
    return measure(machines=machines, **SWEEP_GRID)


def _signed(v: float) -> str:
    return f"{v:+.2f}".replace("-", "−")


def render(df: pd.DataFrame) -> list[str]:
    """Per machine and speed: the runs whose status is ``ok`` on the presets' noise seed (1)
    and their range over :data:`SEEDS`, and over every seed the worst R̂2 error (end or final
    window) and speed error, and the runs that lost control."""
    if "seed" not in df:  # a table measured on the presets' seed alone
        df = df.assign(seed=1)
    seeds = sorted(df["seed"].unique())
    several = len(seeds) > 1  # the range over the seeds, where there is one
    out = [
        "| machine | speed, pu (rpm) | ok | "
        + (f"ok, seeds {seeds[0]}–{seeds[-1]} | " if several else "")
        + "worst R̂2 error, % | worst speed error, rpm | lost control"
        + (", all seeds |" if several else " |"),
        "|---|---|---|---|---|---|" + ("---|" if several else ""),
    ]
    for m in dict.fromkeys(df["machine"]):
        for s in sorted(df.loc[df["machine"] == m, "speed_pu"].unique()):
            g = df[(df["machine"] == m) & (df["speed_pu"] == s)]
            n_ok = g.groupby("seed")["verdict"].apply(lambda v: int((v == "ok").sum()))
            g1 = g[g["seed"] == seeds[0]]
            r2 = pd.concat([g["R2_error_pct"], g["R2_error_window_pct"]])
            worst_r2 = r2.iloc[int(r2.abs().to_numpy().argmax())]
            worst_n = g["speed_error_rpm"].iloc[int(g["speed_error_rpm"].abs().to_numpy().argmax())]
            rpm = s * g["rated_speed_rpm"].iloc[0]
            out.append(
                f"| {m} | {s:g} ({rpm:.0f}) | {int((g1['verdict'] == 'ok').sum())} of {len(g1)} "
                + (f"| {n_ok.min()}–{n_ok.max()} " if several else "")
                + f"| {_signed(worst_r2)} | {_signed(worst_n)} "
                f"| {int(g['lost_control'].astype(bool).sum())} |"
            )
    return out


register(
    DocTable("realistic-envelope", "envelope.md", "data/realistic_envelope.csv", render, measure)
)
register(
    DocTable(
        "realistic-envelope-grid",
        "envelope.md",
        "data/realistic_envelope_grid.csv",
        render,
        measure_sweep_grid,
    )
)
