"""The paper's verdicts re-measured on a realistic drive.

The reproduction (:mod:`imdrive.studies.paper`) ran on an ideal drive. Here every verdict is
measured again with the non-idealities of the ``*-realistic`` presets, first all together and
then one at a time, at 1000, 150 and 50 rpm with rated load:

* the paper's fuzzy compensator and the injection variant from R̂2(0) = 1.2 R2 and 0.8 R2: final
  R̂2 error, time to 2 %, speed error at the end;
* the detuning law of the uncompensated sensorless drive (speed error = slip × (R̂2/R2 − 1)):
  simulated against predicted at R̂2 = 1.2 R2;
* the saturation bias of the injection variant over speed and load, with the controller's
  constant M̂ and with the commissioned magnetising curve.

The drives named "commissioned" (:data:`COMMISSIONED`) run the controller a commissioning
gives, as the ``*-realistic`` presets do: ``[controller_model]`` from
:func:`imdrive.analysis.commissioning.ideal_commissioning` of the drive's own plant.

Every run goes through the batch engine (:func:`imdrive.run.batch.simulate_batch`): the
study took 13.5–13.7 s in 2 runs on a shared 2-core VM (2026-11-22, before the commissioned
drives were added). :func:`compensation_runs`, :func:`detuning_runs` and
:func:`saturation_bias_runs` return the tables; ``imdrive paper`` does not run them;
``python -m imdrive.studies.realistic OUT`` writes the CSVs and ``realistic_verdicts.md``, the
Markdown tables of docs/paper-reproduction.md.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd

from imdrive.analysis import detuning_speed_error_rpm
from imdrive.analysis.commissioning import ideal_commissioning
from imdrive.config.scenario import Scenario
from imdrive.run.batch import simulate_batch
from imdrive.run.metrics import compensation_metrics

RATED_LOAD_NM = 12.0

#: The non-idealities of the realistic presets, each as the overrides that switch it on.
NON_IDEALITIES = {
    "switching": ["inverter.model=switching"],
    "dead time": [
        "inverter.model=switching",
        "inverter.dead_time_s=2e-6",
        "inverter.device_drop_V=1.0",
        "control.dead_time_compensation=feedforward",
        "control.dead_time_compensation_s=1.6e-6",
    ],
    "delay": ["control.delay_periods=1", "control.delay_compensation=true"],
    "sensors": [
        "sensor.gain_a=1.0025",
        "sensor.gain_b=0.9975",
        "sensor.offset_a_A=0.02",
        "sensor.offset_b_A=-0.02",
        "sensor.noise_rms_A=0.02",
        "sensor.adc_bits=12",
        "sensor.adc_range_A=50",
        "sensor.seed=1",
    ],
    "saturation": ["plant.saturation.enabled=true"],
}
DRIVES = {
    "ideal": [],
    **{f"+ {k} only": v for k, v in NON_IDEALITIES.items()},
    "realistic (all)": sorted({o for v in NON_IDEALITIES.values() for o in v}),
}
#: Drives whose controller is commissioned: the tables of
#: :func:`imdrive.analysis.commissioning.ideal_commissioning` (the plant's magnetising curve, its
#: inverter's voltage error) in ``[controller_model]``, as the ``*-realistic`` presets have.
COMMISSIONED = {
    "+ saturation only, commissioned": NON_IDEALITIES["saturation"],
    "+ dead time only, commissioned": NON_IDEALITIES["dead time"],
    "realistic (all), commissioned": DRIVES["realistic (all)"],
}
DRIVES.update(COMMISSIONED)


def read(preset: str, overrides: list[str], drive: str) -> Scenario:
    """The scenario of ``preset`` with ``overrides``; on a commissioned drive with its
    controller's tables from an ideal commissioning of that scenario's plant."""
    sc = Scenario.read(preset, overrides)
    if drive not in COMMISSIONED:
        return sc
    tables = ideal_commissioning(sc)
    extra = [f"controller_model.{k}=[{', '.join(map(repr, v))}]" for k, v in tables.items()]
    return Scenario.read(preset, [*overrides, *extra])


def _speed(rpm: float) -> list[str]:
    """The presets' speed ramp (from 0.5 s, over 1 s) to ``rpm`` instead of 1000."""
    ramp = f"{{ at = 0.5, to = {rpm}, over = 1.0 }}"
    return [f"control.speed_ref_rpm={{ initial = 0, changes = [{ramp}] }}"]


def _load(torque_Nm: float) -> str:
    """The presets' load step at 2 s to ``torque_Nm`` instead of the rated 12 N m."""
    return f"load.torque_Nm={{ initial = 0, changes = [{{ at = 2.0, to = {torque_Nm} }}] }}"


def compensation_runs(speeds=(1000.0, 150.0, 50.0), drives=None) -> pd.DataFrame:
    """Both compensators from ±20 % at every speed on every drive; one row per run."""
    drives = DRIVES if drives is None else drives
    cases = []
    for drive, ov in drives.items():
        for comp in ("paper", "injection"):
            for sign, fig in ((+1, "fig5"), (-1, "fig6")):
                for rpm in speeds:
                    preset = f"{comp}-{fig}"
                    sc = read(preset, [*ov, *_speed(rpm), "output.figures=false"], drive)
                    cases.append((drive, comp, sign * 20, rpm, sc))
    batch = simulate_batch([c[-1] for c in cases], logs=True, log_every=10)
    rows = []
    for (drive, comp, err0, rpm, _), res in zip(cases, batch.results, strict=True):
        m = compensation_metrics(res) or {}
        rows.append(
            {
                "drive": drive,
                "compensator": comp,
                "R2_error_initial_pct": err0,
                "speed_rpm": rpm,
                "diverged": res.diverged,
                "R2_error_final_pct": m.get("R2_hat_final_error_pct", np.nan),
                "time_to_2pct_s": m.get("time_to_tolerance_s"),
                "speed_error_after_rpm": m.get("speed_error_after_rpm", np.nan),
                "speed_ripple_after_rpm": m.get("speed_ripple_after_rpm", np.nan),
            }
        )
    return pd.DataFrame(rows)


def saturation_bias_runs(speeds=(1000.0, 150.0, 95.0, 50.0), loads=(3.4, 12.0)) -> pd.DataFrame:
    """The injection variant on the saturating machine alone, with the constant M̂ and with
    the commissioned curve, from ±20 % at each speed and load: the final R̂2 error."""
    cases = []
    for drive in ("+ saturation only", "+ saturation only, commissioned"):
        for rpm in speeds:
            for load in loads:
                for sign, fig in ((+1, "fig5"), (-1, "fig6")):
                    ov = [
                        *DRIVES[drive],
                        *_speed(rpm),
                        _load(load),
                        "output.figures=false",
                    ]
                    cases.append((drive, rpm, load, sign * 20, read(f"injection-{fig}", ov, drive)))
    batch = simulate_batch([c[-1] for c in cases], logs=True, log_every=10)
    rows = []
    for (drive, rpm, load, err0, _), res in zip(cases, batch.results, strict=True):
        m = compensation_metrics(res) or {}
        rows.append(
            {
                "drive": drive,
                "speed_rpm": rpm,
                "load_Nm": load,
                "R2_error_initial_pct": err0,
                "diverged": res.diverged,
                "R2_error_final_pct": m.get("R2_hat_final_error_pct", np.nan),
                "speed_error_after_rpm": m.get("speed_error_after_rpm", np.nan),
            }
        )
    return pd.DataFrame(rows)


def detuning_runs(speeds=(1000.0, 150.0, 50.0), ratio=1.2, drives=None) -> pd.DataFrame:
    """The uncompensated sensorless drive with R̂2 = ratio·R2: simulated vs the detuning law."""
    drives = DRIVES if drives is None else drives
    cases = []
    for drive, ov in drives.items():
        for rpm in speeds:
            sc = read(
                "sensorless",
                [
                    *ov,
                    *_speed(rpm),
                    f"estimator.R2_ohm={ratio * 0.816}",
                    "simulation.t_end_s=4.0",
                    "output.figures=false",
                ],
                drive,
            )
            cases.append((drive, rpm, sc))
    batch = simulate_batch([c[-1] for c in cases], window_s=0.5)
    rows = []
    for (drive, rpm, sc), (_, row) in zip(cases, batch.metrics.iterrows(), strict=True):
        law = detuning_speed_error_rpm(sc.machine, rpm, RATED_LOAD_NM, ratio)
        rows.append(
            {
                "drive": drive,
                "speed_rpm": rpm,
                "diverged": bool(row["diverged"]),
                "speed_error_rpm": row["speed_error_rpm"],
                "detuning_law_rpm": float(law),
                "ripple_rpm": row["speed_ripple_rpm"],
            }
        )
    return pd.DataFrame(rows)


def _cell(v, fmt: str) -> str:
    missing = v is None or (isinstance(v, float) and np.isnan(v))
    return "—" if missing else format(v, fmt)


def compensation_markdown(comp: pd.DataFrame) -> list[str]:
    """The lines of the compensators' table (:func:`compensation_runs`' rows)."""
    f = _cell
    lines = [
        "| drive | compensator | speed, rpm | final R̂2 error from +20 % / −20 %, % "
        "| time to 2 %, s (+20 / −20) | speed error at the end, rpm (+20 / −20) |",
        "|---|---|---|---|---|---|",
    ]
    for (drive, compn, rpm), g in comp.groupby(["drive", "compensator", "speed_rpm"], sort=False):
        p = g[g.R2_error_initial_pct > 0].iloc[0]
        n = g[g.R2_error_initial_pct < 0].iloc[0]
        lines.append(
            f"| {drive} | {compn} | {rpm:g} "
            f"| {f(p.R2_error_final_pct, '+.1f')} / {f(n.R2_error_final_pct, '+.1f')} "
            f"| {f(p.time_to_2pct_s, '.1f')} / {f(n.time_to_2pct_s, '.1f')} "
            f"| {f(p.speed_error_after_rpm, '+.2f')} / {f(n.speed_error_after_rpm, '+.2f')} |"
        )
    return lines


def detuning_markdown(det: pd.DataFrame) -> list[str]:
    """The lines of the detuning law's table (:func:`detuning_runs`' rows)."""
    lines = [
        "| drive | speed, rpm | speed error with R̂2 = 1.2 R2, rpm | detuning law, rpm |",
        "|---|---|---|---|",
    ]
    for _, r in det.iterrows():
        sim = "diverged" if r.diverged else f"{r.speed_error_rpm:+.2f}"
        lines.append(f"| {r.drive} | {r.speed_rpm:g} | {sim} | {r.detuning_law_rpm:+.2f} |")
    return lines


def markdown(comp: pd.DataFrame, det: pd.DataFrame) -> str:
    """The two tables as Markdown (the docs' section "On a realistic drive")."""
    return "\n".join([*compensation_markdown(comp), "", *detuning_markdown(det)]) + "\n"


def bias_markdown(bias: pd.DataFrame) -> str:
    """The saturation-bias table as Markdown."""
    lines = [
        "| controller | speed, rpm | load, N m | final R̂2 error from +20 % / −20 %, % "
        "| speed error at the end, rpm (+20 / −20) |",
        "|---|---|---|---|---|",
    ]
    for (drive, rpm, load), g in bias.groupby(["drive", "speed_rpm", "load_Nm"], sort=False):
        p = g[g.R2_error_initial_pct > 0].iloc[0]
        n = g[g.R2_error_initial_pct < 0].iloc[0]
        ctl = "commissioned curve" if "commissioned" in drive else "constant M̂"
        lines.append(
            f"| {ctl} | {rpm:g} | {load:g} "
            f"| {p.R2_error_final_pct:+.1f} / {n.R2_error_final_pct:+.1f} "
            f"| {p.speed_error_after_rpm:+.2f} / {n.speed_error_after_rpm:+.2f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    """``python -m imdrive.studies.realistic [OUT_DIR]``: the three studies, their CSVs and
    the verdicts' page in ``OUT_DIR`` (default ``out/realistic``)."""
    import argparse

    ap = argparse.ArgumentParser(
        prog="python -m imdrive.studies.realistic", description=__doc__.splitlines()[0]
    )
    ap.add_argument("out_dir", nargs="?", default="out/realistic", help="(default %(default)s)")
    out = Path(ap.parse_args(sys.argv[1:] if argv is None else argv).out_dir)
    out.mkdir(parents=True, exist_ok=True)
    comp = compensation_runs()
    det = detuning_runs()
    bias = saturation_bias_runs()
    comp.to_csv(out / "realistic_compensation.csv", index=False)
    det.to_csv(out / "realistic_detuning.csv", index=False)
    bias.to_csv(out / "realistic_saturation_bias.csv", index=False)
    text = markdown(comp, det) + "\n" + bias_markdown(bias)
    (out / "realistic_verdicts.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
