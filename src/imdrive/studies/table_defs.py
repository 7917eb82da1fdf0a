"""The result tables of ``docs/`` that :mod:`imdrive.studies.doctables` generates: for each, its
renderer (Markdown lines from the data file) and the measurement that writes the data file."""

from __future__ import annotations

import math

from imdrive.studies.doctable import DocTable, register


def _signed(v: float, digits: int = 2) -> str:
    """``+0.23``, ``−14.60`` (a true minus sign, as the pages write)."""
    return f"{v:+.{digits}f}".replace("-", "−")


def _pair(a: float, b: float, digits: int = 2) -> str:
    return f"{_signed(a, digits)} / {_signed(b, digits)}"


def _lazy(module: str, attr: str):
    """``imdrive.studies.<module>.<attr>``, imported when called (a study's module imports the
    kernels and the runs: listing or checking the tables does not need them)."""

    def call(*args, **kwargs):
        import importlib

        return getattr(importlib.import_module(f"imdrive.studies.{module}"), attr)(*args, **kwargs)

    call.__qualname__ = call.__name__ = f"{module}.{attr}"
    return call


def study_table(name: str, page: str, data: str, module: str, render: str, measure: str) -> None:
    """Register the table ``name`` of ``docs/<page>`` whose renderer (``df -> lines``) and
    measurement are the functions ``render`` and ``measure`` of ``imdrive.studies.<module>``."""
    register(DocTable(name, page, data, _lazy(module, render), _lazy(module, measure)))


# ---------------------------------------------------------------------------------------------
# docs/paper-reproduction.md, "On a realistic drive" (imdrive.studies.realistic)


study_table(
    "realistic-compensation",
    "paper-reproduction.md",
    "data/realistic_compensation.csv",
    "realistic",
    "compensation_markdown",
    "compensation_runs",
)


def _realistic_saturation_bias(df) -> list[str]:
    from imdrive.studies.realistic import bias_markdown

    return bias_markdown(df).rstrip("\n").split("\n")


def _measure_realistic_saturation_bias():
    from imdrive.studies.realistic import saturation_bias_runs

    return saturation_bias_runs()


register(
    DocTable(
        "realistic-saturation-bias",
        "paper-reproduction.md",
        "data/realistic_saturation_bias.csv",
        _realistic_saturation_bias,
        _measure_realistic_saturation_bias,
    )
)

study_table(
    "realistic-detuning",
    "paper-reproduction.md",
    "data/realistic_detuning.csv",
    "realistic",
    "detuning_markdown",
    "detuning_runs",
)


# ---------------------------------------------------------------------------------------------
# docs/paper-reproduction.md, "Gating and the blind band" (imdrive.studies.gating)


def _blind_band(df) -> list[str]:
    out = [
        "| operating point | f_e | final R̂2 error without → with gating, % (from +15 / −15 %) "
        "| speed error at the end with gating, rpm |",
        "|---|---|---|---|",
    ]
    for (speed, load), g in df.groupby(["speed_rpm", "load_Nm"], sort=False):
        regen = " (regenerating)" if load < 0 else ""
        point = f"{speed:g} rpm, {load:g} N m".replace("-", "−")

        def err(gating, col, g=g):
            rows = g[g.gating == gating].sort_values("R2_ratio_initial", ascending=False)
            vals = [math.nan if d else v for d, v in zip(rows.diverged, rows[col], strict=True)]
            return vals

        off, on = err(False, "R2_error_final_pct"), err(True, "R2_error_final_pct")
        speed_err = err(True, "speed_error_rpm")
        out.append(
            f"| {point}{regen} | {g.f_e_Hz.iloc[0]:.1f} Hz "
            f"| {_pair(*off)} → {_pair(*on)} | {_pair(*speed_err)} |".replace("nan", "diverged")
        )
    return out


def _measure_blind_band():
    from imdrive.studies.gating import blind_band_runs

    return blind_band_runs()


register(
    DocTable(
        "blind-band",
        "paper-reproduction.md",
        "data/blind_band.csv",
        _blind_band,
        _measure_blind_band,
    )
)


# ---------------------------------------------------------------------------------------------
# docs/estimators.md, "Performance" (benchmarks/bench_estimators.py --csv)


def _estimator_timing(df) -> list[str]:
    out = ["| estimator | × real time, slowest–fastest run | runs |", "|---|---|---|"]
    for name, g in df.groupby("estimator", sort=False):
        rtf = g.simulated_s / g.wall_s
        out.append(f"| {name} | {rtf.min():.0f}–{rtf.max():.0f} | {len(g)} |")
    return [*out, "", f"Preset `{df.preset.iloc[0]}`; {df.machine.iloc[0]}."]


register(
    DocTable(
        "estimator-timing",
        "estimators.md",
        "data/estimator_timing.csv",
        _estimator_timing,
        None,
        "python benchmarks/bench_estimators.py --csv docs/data/estimator_timing.csv",
    )
)


# ---------------------------------------------------------------------------------------------
# docs/estimators.md, "Low speed on the realistic drive" (imdrive.bench)

#: the low-speed bench: every estimator with its defaults on the commissioned realistic drive
LOW_SPEED_ESTIMATORS = ("mras", "smo-mras", "ekf", "afo", "reactive-mras")
LOW_SPEEDS_RPM = (45, 70, 100)
LOW_SPEED_LOADS_NM = (12, 6, 0, -6, -12)


def _case_point(case: str) -> tuple[float, float]:
    """``(speed, load)`` of a ``steady-<rpm>rpm-<N m>Nm`` case, rpm and N m."""
    _, rpm, load = case.split("-", 2)
    return float(rpm.removesuffix("rpm")), float(load.removesuffix("Nm"))


def low_speed_stator_frequency_Hz(case: str) -> float:
    """The steady state's stator frequency of a low-speed bench case on
    ``sensorless-realistic`` with R2_hat = R2, Hz
    (:func:`imdrive.analysis.drive_steady_state.stator_frequency_Hz`): where it is within
    :data:`imdrive.run.status.LOW_FREQUENCY_PU` of the rated frequency of zero, a run's status
    says it ran near zero stator frequency."""
    from imdrive.analysis.drive_steady_state import stator_frequency_Hz
    from imdrive.config.scenario import Scenario

    speed, load = _case_point(case)
    return stator_frequency_Hz(Scenario.read("sensorless-realistic"), speed, load, 1.0)


def _measure_low_speed():
    from imdrive.bench.protocol import ESTIMATORS, Run, steady_cases
    from imdrive.bench.report import run_protocol

    cases = steady_cases(LOW_SPEEDS_RPM, LOW_SPEED_LOADS_NM)
    drives = {"sensorless-realistic": "sensorless-realistic"}
    runs = [
        Run(e, c, "sensorless-realistic")
        for e in LOW_SPEED_ESTIMATORS
        if e in ESTIMATORS
        for c in cases
    ]
    table, _, _ = run_protocol(runs=runs, cases=cases, drives=drives)
    f_s = {c: low_speed_stator_frequency_Hz(c) for c in cases}
    table["f_s_Hz"] = table["case"].map(f_s)
    return table


def _low_speed(df) -> list[str]:
    ests = [e for e in LOW_SPEED_ESTIMATORS if e in set(df.estimator)]
    out = ["| case | f_s, Hz | " + " | ".join(ests) + " |", "|---" * (len(ests) + 2) + "|"]
    for case in dict.fromkeys(df.case):
        rpm, load = _case_point(case)
        name = f"{rpm:g} rpm, " + ("0" if load == 0 else f"{_signed(load, 0)} N m")
        f_s = df[df.case == case].f_s_Hz.iloc[0]
        cells = []
        for e in ests:
            r = df[(df.case == case) & (df.estimator == e)].iloc[0]
            lost = bool(r.lost_control) or bool(r.diverged)
            cells.append("**lost**" if lost else _signed(r.steady_speed_error_rpm, 1))
        out.append(f"| {name} | {_signed(f_s, 1)} | " + " | ".join(cells) + " |")
    return out


register(
    DocTable(
        "estimator-low-speed",
        "estimators.md",
        "data/estimator_low_speed.csv",
        _low_speed,
        _measure_low_speed,
    )
)

# ---------------------------------------------------------------------------------------------
# docs/nameplate.md: nameplate -> circuit on the library (imdrive.studies.nameplate_check)


study_table(
    "nameplate-check",
    "nameplate.md",
    "data/nameplate_check.csv",
    "nameplate_check",
    "markdown",
    "run",
)


study_table(
    "nameplate-published",
    "nameplate.md",
    "data/nameplate_published.csv",
    "nameplate_published",
    "markdown",
    "run",
)


# docs/nameplate.md: the default rotor inertia against catalogue motors
# (imdrive.studies.inertia_catalogue)


study_table(
    "inertia-catalogue",
    "nameplate.md",
    "data/inertia_catalogue.csv",
    "inertia_catalogue",
    "markdown",
    "run",
)

# ---------------------------------------------------------------------------------------------
# docs/machine-envelope.md: why the large machines lose control at rated speed


study_table(
    "machine-ramp-diagnosis",
    "machine-envelope.md",
    "data/machine_ramp_diagnosis.csv",
    "machines",
    "diagnosis_markdown",
    "ramp_diagnosis",
)


# ---------------------------------------------------------------------------------------------
# docs/machine-envelope.md: regenerating at low speed, by stator frequency


study_table(
    "zero-frequency",
    "machine-envelope.md",
    "data/zero_frequency.csv",
    "zero_frequency",
    "markdown_lines",
    "run",
)


study_table(
    "zero-frequency-R1",
    "machine-envelope.md",
    "data/zero_frequency_R1.csv",
    "zero_frequency",
    "r1_sensitivity_lines",
    "r1_sensitivity",
)


study_table(
    "detection-gain",
    "machine-envelope.md",
    "data/detection_gain.csv",
    "detection_gain",
    "markdown_lines",
    "measure",
)


study_table("library-tour", "machines.md", "data/library_tour.csv", "tour", "lines", "run")


from imdrive.studies import (  # noqa: E402, F401  (register theirs)
    compensator_tables,
    r2_law_tables,
    realistic_envelope,
    robust_tables,
    stability_tables,
)
