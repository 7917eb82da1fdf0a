"""``imdrive run``: one drive from a preset, a scenario file or a run's summary.json."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from imdrive.cli._common import (
    EXIT_DIVERGED,
    EXIT_LOST_CONTROL,
    EXIT_OK,
    _examples,
    add_allow_plugins,
    output_folder,
)


def _run_folder_name(preset_or_file: str) -> str:
    """The default folder name of ``imdrive run``: a preset's name, or the file's own name
    without its suffix (``my.toml`` -> ``out/my``), not the scenario's ``name``; for a run's
    ``summary.json``, its folder's name + ``-rerun`` (``out/my/summary.json`` -> ``out/my-rerun``).
    """
    from imdrive.config.presets import preset_names

    if preset_or_file in preset_names():
        return preset_or_file
    path = Path(preset_or_file)
    if path.suffix == ".json":  # a run's summary.json: beside that run, never over it
        return f"{path.resolve().parent.name}-rerun"
    return path.stem


def mode_text(scenario) -> str:
    """How the scenario drives the machine, in a few words (the console's running line)."""
    if scenario.drive.mode == "vector":
        return f"vector control, speed feedback {scenario.control.speed_feedback}"
    ol = scenario.open_loop
    how = f"V/f ramp {ol.vf_ramp_s:g} s" if ol.vf_ramp_s > 0 else "direct on line"
    return f"open loop, {how}"


def open_loop_note(scenario) -> str:
    """``"; open loop: ..."`` for a scenario that runs open-loop, else ``""``: a file without
    ``[drive] mode = "vector"`` runs the machine on the ``[open_loop]`` voltage and ignores
    ``[control]``, ``[estimator]`` and ``[compensator]``."""
    if scenario.drive.mode == "vector":
        return ""
    return (
        '; open loop ([drive] mode is not "vector": the machine on the [open_loop] voltage, '
        "[control] and the estimator unused)"
    )


def _cmd_run(args) -> int:
    from imdrive.config.scenario import Scenario
    from imdrive.run.build import build_arrays
    from imdrive.run.files import owns_result_file
    from imdrive.run.simulate import simulate

    scenario = Scenario.read(args.scenario, args.set or [])
    if args.format:  # an unknown format is bad input before anything runs
        from imdrive.run.formats import formats_wanted

        formats_wanted([f.strip() for s in args.format for f in s.split(",") if f.strip()])
    out = output_folder(
        args.out,
        _run_folder_name(args.scenario),
        owns=owns_result_file,
        force=args.force,
        what="an imdrive result",
    )
    arrays = build_arrays(scenario)  # every derived quantity checked before anything runs
    if not args.quiet:
        print(
            f"imdrive: running {scenario.name} ({scenario.simulation.t_end_s:g} s, "
            f"{mode_text(scenario)}) ...",
            file=sys.stderr,
        )
    formats = None
    if args.format:
        formats = [f.strip() for spec in args.format for f in spec.split(",") if f.strip()]
    # the recording is taken during the run: --format recording asks for it too
    res = simulate(scenario, arrays, record=None if formats is None else "recording" in formats)
    res.save(out, force=args.force, formats=formats)
    s = res.summary()
    if res.diverged or res.lost_control:
        from imdrive.run.diagnosis import closing_line

        done = "partial results" if res.diverged else "results"
        print(f"imdrive: error: {closing_line(res, out)} ({done} in {out})", file=sys.stderr)
        return EXIT_DIVERGED if res.diverged else EXIT_LOST_CONTROL
    if not args.quiet:
        fin = s["final"]
        print(
            f"imdrive: done in {time.perf_counter() - args.t0:.1f} s (simulation "
            f"{res.wall_time_s:.3f} s, {s['real_time_factor']:.0f}x real time); final speed "
            f"{fin['speed_rpm']:.2f} rpm, torque {fin['torque_Nm']:.3f} N m"
            f"{open_loop_note(scenario)} -> {out}",
            file=sys.stderr,
        )
    if s["verdict"].get("R2_held_note"):  # with -q too: a hold is part of the status
        print(f"imdrive: {s['verdict']['R2_held_note']}", file=sys.stderr)
    if s["verdict"].get("R2_R1_note"):  # with -q too: so is R2's observability
        print(f"imdrive: {s['verdict']['R2_R1_note']}", file=sys.stderr)
    if s["verdict"]["verdict"] != "ok":  # completed, but R2_hat or the speed is not right
        from imdrive.run.diagnosis import closing_line

        print(f"imdrive: status: {closing_line(res, out)}", file=sys.stderr)
    return EXIT_OK


def add_parser(sub) -> None:
    """Register ``imdrive run``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``imdrive`` parser's sub-commands.
    """
    r = sub.add_parser(
        "run",
        help="run a preset or scenario file",
        description="Run one drive: a built-in preset by name, a scenario TOML file, or a "
        "run's summary.json (to run it again). Writes timeseries.csv, summary.json and "
        "report.html (interactive plots; open it in a browser), and the PNG figures when asked "
        "(--format csv,report,figures or [output] figures = true), into out/PRESET, or "
        "out/FILE for a file named FILE.toml, unless --out says otherwise. Exit codes: "
        "imdrive --help.",
        epilog=_examples(
            "imdrive run sensorless",
            "imdrive run sensorless --set simulation.t_end_s=2 --set load.torque_Nm=6",
            "imdrive run my.toml --out results/my-run",
            "imdrive run out/sensorless/summary.json",
            "imdrive run sensorless --format parquet,mat,report",
            "imdrive run sensorless --format csv,report,figures",
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    r.add_argument("scenario", metavar="PRESET_OR_FILE")
    r.add_argument(
        "--out", metavar="DIR", help="output folder (default out/PRESET, or out/FILE for FILE.toml)"
    )
    r.add_argument(
        "--set",
        action="append",
        metavar="KEY.PATH=VALUE",
        help="override a scenario value, e.g. --set simulation.t_end_s=2 (repeatable)",
    )
    r.add_argument(
        "--format",
        action="append",
        metavar="NAME[,NAME]",
        help="write exactly these outputs besides summary.json, whatever [output] says: "
        "csv, mat, parquet, figures, report, recording (repeatable)",
    )
    r.add_argument(
        "--force",
        action="store_true",
        help="replace an --out folder that holds files other than an imdrive result",
    )
    r.add_argument("-q", "--quiet", action="store_true")
    add_allow_plugins(r)
    r.set_defaults(func=_cmd_run)
