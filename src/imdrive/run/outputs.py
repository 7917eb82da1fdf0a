"""The output reference: every column ``imdrive run`` writes, every key of summary.json, every
column of the batch and sweep tables, with its meaning, frame, sign and unit.

Generated into ``docs/outputs.md`` (``python -m imdrive.run.outputs [--check]``) from the same
tables the results are built from, so it cannot go stale: ``tests/run/test_exports.py`` fails when
the file differs or when a written column has no entry here.
"""

from __future__ import annotations

import sys
from pathlib import Path

from imdrive.config.output import OutputSettings
from imdrive.run.columns import OPEN_LOOP_COLUMNS, RENAMED_COLUMNS, VECTOR_COLUMNS, unit_of
from imdrive.run.formats import output_formats

#: meaning of each exported column (frame, sign convention); the unit is the name's suffix
COLUMN_DOCS = {
    "time_s": "sample time t_k = k Ts (the samples at the start of each control period)",
    "speed_rpm": "mechanical speed of the plant (positive: forward)",
    "w_m_rad_s": "the same speed in SI",
    "torque_Nm": "electromagnetic torque T_e = 1.5 n_p (psi_s x i_s) of the plant",
    "load_torque_Nm": "load torque T_L (positive opposes forward motion)",
    "i_a_A": "plant stator current of phase a (true, not measured)",
    "i_b_A": "phase b",
    "i_c_A": "phase c",
    "i_alpha_A": "plant stator current, stationary alpha axis (amplitude-invariant Clarke: "
    "equals i_a)",
    "i_beta_A": "plant stator current, stationary beta axis",
    "i_alpha_meas_A": "stator current as the sensors report it, alpha (what the controller uses)",
    "i_beta_meas_A": "measured stator current, beta",
    "psi_r_alpha_Wb": "plant rotor flux linkage (stator-referred), alpha",
    "psi_r_beta_Wb": "plant rotor flux linkage, beta",
    "v_alpha_V": "period-average stator voltage applied at the terminals over [t_k, t_k + Ts), "
    "alpha (dead time and drops included; at the last sample: the commanded one)",
    "v_beta_V": "the same, beta",
    "v_ref_alpha_V": "voltage reference the controller computed at sample k, alpha "
    "(dead-time compensation included, before the computation delay)",
    "v_ref_beta_V": "the same, beta",
    "R1_ohm": "plant stator resistance (profile and temperature)",
    "R2_ohm": "plant rotor resistance (profile and temperature)",
    "flux_Wb": "magnitude of the plant's rotor flux |psi_r|",
    "theta1_C": "stator winding temperature",
    "theta2_C": "rotor winding temperature",
    "speed_ref_rpm": "speed reference",
    "speed_est_rpm": "speed estimate of the MRAS (mechanical)",
    "id_ref_A": "flux-current reference id* in the controller's frame (injection included)",
    "iq_ref_A": "torque-current reference iq*",
    "i_d_A": "measured current in the controller's synchronous frame, d",
    "i_q_A": "measured current in the controller's synchronous frame, q",
    "R2_hat_ohm": "the controller's rotor-resistance estimate R2_hat",
    "R1_hat_ohm": "the controller's stator-resistance estimate R1_hat (constant unless "
    "mras.R1_rate_per_s or mras.R1_rate_pu > 0, or the AFO adapts it)",
    "e_d0_Wb": "MRAS flux error (reference minus adjustable model) in the controller's frame, d "
    "(the paper's e_d0; negative when R2_hat > R2 by the paper's reading)",
    "e_q0_Wb": "the same, q",
    "theta_e_rad": "the controller's field angle at the sample, wrapped to [-pi, pi)",
    "lam_v_alpha_Wb": "MRAS reference (voltage) model rotor flux, filtered, alpha",
    "lam_v_beta_Wb": "the same, beta",
    "lam_i_alpha_Wb": "MRAS adjustable (current) model rotor flux through the same filter, alpha",
    "lam_i_beta_Wb": "the same, beta",
    "e_d0_demod_Wb": "e_d0 detected synchronously with the injected sinusoid (2 e_d0 sin), the "
    "injection compensator's input",
    "comp_frozen_flags": "why the compensator's last decision was frozen, a bit mask: 1 speed "
    "error or reference moving, 2 load (iq*) change, 4 voltage limit, 8 injection frequency "
    "switched, 64 the injection started (a model-based law), 16 within the hold periods after "
    "any of these, 32 the injection backed off near the voltage limit (R2 not observable "
    "there), 128 the detection's modelled response to R2 not positive (a model-based law; R2 "
    "not observable there) (0: R2_hat updated); see imdrive.kernels.gating and "
    "imdrive.kernels.r2_kalman",
    "comp_live_flag": "1 when the compensator's last decision estimated R2_hat from the "
    "detected error; 0 when R2_hat was held (before its start, frozen by the gating: "
    "comp_frozen_flags says why, or its window refilling after a freeze)",
    "rotor_rise_K": "the compensator's rotor thermal model: rotor temperature above ambient "
    "(compensator.thermal_model; recalibrated by the estimate, it carries R2_hat while held)",
    "R1_id_status_code": "standstill R1 identification (mras.R1_standstill): 0 no standstill "
    "run yet, 1 R1_hat identified, 2 a standstill run ended before the measured flux build-up "
    "was over, or the drive was not still (R1_hat left as it was; the run's verdict_text says "
    "so), 3 the two-level test identified its first level only (R1_hat holds the inverter's "
    "residual, as with one level)",
    "inj_freq_Hz": "injection frequency in use (the compensator moves it away from the stator "
    "frequency)",
}

SUMMARY_DOCS = {
    "scenario": "the scenario as run, every default filled in (a valid scenario file's "
    "content); no absolute path: a machine file's values are inlined (`file` null), a plug-in "
    "module's path is relative to the result folder",
    "derived": "quantities derived from it: gains, limits, rated values, compensator period",
    "resolved": "the value each unset scenario-dependent setting took (field weakening, "
    "current controller, speed-gain scaling, MRAS type, the compensator's machine-scaled "
    "gains): what `imdrive show --all` writes in their comments",
    "versions": "imdrive, Python, numpy, scipy, numba versions",
    "status": "ok, or why the run stopped",
    "diverged": "whether a state left its bounds (NaN, current, speed)",
    "diverged_at_s": "when (null if not diverged)",
    "diverged_signal": "which signal crossed its bound",
    "simulated_time_s": "simulated time",
    "control_periods": "control periods simulated",
    "wall_time_s": "wall time of the kernel alone",
    "kernel_startup_s": "loading (or compiling) the kernels",
    "real_time_factor": "simulated time / kernel wall time",
    "final": "every column's value at the last sample",
    "energy_J": "energy accumulators of the plant: input, copper loss, air-gap work, load and "
    "friction work, change of magnetic and kinetic energy",
    "compensation": "how the R2 compensator did (null when it is off): see "
    "imdrive.run.metrics.compensation_metrics",
    "machine_rated": "the machine's rated point: nameplate where given, else derived from the "
    "circuit (voltage, frequency, speed, slip, torque, current, power factor, efficiency, "
    "magnetising current, rotor flux, breakdown torque): imdrive.config.machine.rated_point",
    "verdict": "the run's status (imdrive.run.status): `verdict` ok, or the cause of a "
    "failure (lost-control, diverged, frozen, held, R2-off, R2-unsettled, speed-error: the "
    "mean speed error beyond its tolerance, or the speed swinging by more than ten times it "
    "over a settled final window): a loss "
    "of control or divergence whenever there is one, else the first in time, "
    "`verdict_text` every "
    "cause in time order, `verdict_at_s`; the speed error in rated slips and its tolerance; "
    "the share of the compensator's time R2_hat was held, since when and why (voltage limit, "
    "stator frequency band, injection start, gated transient), `R2_held_by_cause_pct` the "
    "share per cause, and "
    "`R2_held_note`, the sentence the console prints whenever R2_hat was held more than 10 % "
    "of the time; `R2_observable`: estimated at the end, or not "
    "observable here and why; `R2_R1_sensitivity`, how many % R2_hat moves per % of R1_hat "
    "error at the final operating point (imdrive.analysis.observability), and `R2_R1_note`, "
    "the sentence the console prints when a 1 % R1 error would move R2_hat beyond the R2 "
    "tolerance",
    "plugins": "each module of `[plugins] modules` (a file's path relative to the result "
    "folder) -> the sha256 of its file (null: not readable); a rerun of this summary.json warns "
    "when a module has changed since",
}


def _file_rows() -> list[str]:
    """One table row per registered output format."""
    defaults = OutputSettings()
    rows = []
    for f in output_formats():
        files = ", ".join(f"`{name}`" for name in f.files)
        default = "true" if getattr(defaults, f.key) else "false"
        rows.append(f"| {files} | `{f.key}` | {default} | {f.description} |")
    return rows


def markdown() -> str:
    """The output reference as Markdown."""
    lines = [
        "# Outputs",
        "",
        "<!-- generated by `python -m imdrive.run.outputs`; do not edit -->",
        "",
        "What `imdrive run` writes into its folder: `summary.json` and the files of the"
        " formats its `[output]` table turns on (*Files* below); the time-series files hold the"
        " same columns with their units. Space vectors use the amplitude-invariant Clarke"
        " transform; the unit is the column name's suffix.",
        "",
        "One row is logged every `simulation.log_every` control periods; by default as many"
        " periods as keep the log at 1 kHz or faster (10 at Ts = 100 µs), enough for everything"
        " up to the current loop. A 14 s vector drive then writes a 5.6 MB CSV (56 MB at"
        " `log_every = 1`). For long or full-rate runs, Parquet is the format:"
        " `[output] parquet = true` (exact float64, zstd-compressed, reads 2-3 times faster"
        " than the CSV) and `csv = false` to skip the CSV (it is written by default, so"
        " existing scripts keep working).",
        "",
        "## Files",
        "",
        "`summary.json` always; each other file when its `[output]` key is true"
        " (`imdrive.run.formats`, one module per format).",
        "",
        "| file | `[output]` key | default | content |",
        "|---|---|---|---|",
        *_file_rows(),
        "",
        "## Time-series columns",
        "",
        "Open-loop runs write the first group; vector-controlled runs add the second.",
        "",
        "| column | unit | meaning |",
        "|---|---|---|",
    ]
    for name in OPEN_LOOP_COLUMNS:
        lines.append(f"| `{name}` | {unit_of(name)} | {COLUMN_DOCS[name]} |")
    lines += ["", "Vector control adds:", "", "| column | unit | meaning |", "|---|---|---|"]
    for name in VECTOR_COLUMNS[len(OPEN_LOOP_COLUMNS) :]:
        lines.append(f"| `{name}` | {unit_of(name)} | {COLUMN_DOCS[name]} |")
    lines += [
        "",
        "### Renamed columns",
        "",
        "Names follow the glossary of docs/architecture.md (`_hat`: an estimate). A renamed"
        " column's old name still answers where a column is read by name"
        " (`SimulationResult.signals`, `res[name]`, `res.window(...)`, `res.plot([...])`), with a"
        " `DeprecationWarning`, until 0.3; the files carry the new name only (a script of your"
        " own that reads `timeseries.csv`: `.rename(columns=imdrive.run.columns.RENAMED_COLUMNS)`"
        " gives an old file the new names; `{new: old for old, new in RENAMED_COLUMNS.items()}`"
        " gives a new file the old ones). The compensation"
        " metrics (`summary.json` `compensation`, `compensation_metrics`) were renamed the"
        " same way (`R2_est_final_ohm` -> `R2_hat_final_ohm`).",
        "",
        "| old column | new column |",
        "|---|---|",
        *(f"| `{old}` | `{new}` |" for old, new in RENAMED_COLUMNS.items()),
    ]
    lines += ["", "## summary.json", "", "| key | meaning |", "|---|---|"]
    lines += [f"| `{k}` | {v} |" for k, v in SUMMARY_DOCS.items()]
    lines += [
        "",
        "## Batch and sweep tables",
        "",
        "One row per drive; the metric columns are defined in `imdrive.run.metrics` (module"
        " docstring) and computed while the samples stream (`imdrive.kernels.batch`); the"
        " status columns (`verdict`, `verdict_ok`, `verdict_text`, `verdict_at_s`,"
        " `speed_error_pu_slip`, `speed_tolerance_rpm`) are those of `imdrive.run.status`.",
        "",
    ]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    """``python -m imdrive.run.outputs [--check]``: write docs/outputs.md (or check it)."""
    import argparse

    ap = argparse.ArgumentParser(
        prog="python -m imdrive.run.outputs", description="Write docs/outputs.md."
    )
    ap.add_argument("--check", action="store_true", help="exit 1 if the page is stale")
    args = ap.parse_args(sys.argv[1:] if argv is None else argv)
    path = Path(__file__).resolve().parents[3] / "docs" / "outputs.md"
    text = markdown()
    if args.check:
        if not path.exists() or path.read_text() != text:
            print(f"{path} is stale: run python -m imdrive.run.outputs", file=sys.stderr)
            return 1
        return 0
    path.write_text(text)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
