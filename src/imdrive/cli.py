"""The ``imdrive`` command.

Exit codes
----------
0 (``EXIT_OK``)
    Done.
1 (``EXIT_DIVERGED``)
    A physical outcome: the run diverged. Its partial results are written, marked
    ``"diverged": true`` in summary.json.
2 (``EXIT_BAD_INPUT``)
    Bad input (an unknown preset, key or type, a value that breaks a rule, a derived quantity
    that overflows, an unsafe name, a sweep above ``--max-runs``, an ``--out`` folder that
    holds other files): one line ``imdrive: error: field: rule`` on stderr, nothing written.
3 (``EXIT_LOST_CONTROL``)
    A physical outcome: the run completed but lost control of the speed (it stayed more than
    ``simulation.lost_control_rpm`` from its reference for ``simulation.lost_control_s``: a
    runaway, a sustained limit cycle). Results written, marked ``"lost_control": true``.
4 (``EXIT_ENVIRONMENT``)
    The environment failed: an I/O error, a full disk, a permission, memory, a path longer
    than the file system allows at write time, a dask cluster that lost its workers or
    scheduler, a sweep store locked by another process. One line naming the cause, no
    traceback; what was already written stays and looks incomplete (no summary.json, a sweep
    manifest without ``"complete": true``; ``--resume`` continues a sweep).
5 (``EXIT_INTERNAL``)
    An unexpected error (a bug): one line; set ``IMDRIVE_DEBUG=1`` for the traceback.
130
    Interrupted (Ctrl-C).

A sweep records its diverging runs (``diverged``, ``status``), those that lost control
(``lost_control``, ``lost_control_at_s``) and the runs that could not be built (``status`` -1,
``error``) in its table and exits 0.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import tomllib
import warnings
from pathlib import Path

from imdrive.errors import ConfigError, ConfigWarning, EnvironmentFailure, describe_os_error

EXIT_OK = 0
EXIT_DIVERGED = 1
EXIT_BAD_INPUT = 2
EXIT_LOST_CONTROL = 3
EXIT_ENVIRONMENT = 4
EXIT_INTERNAL = 5

OUT_ROOT = Path("out")  # default output root: out/NAME, out/sweep-NAME
NAME_MAX_BYTES = 255  # longest file name on common file systems (ext4, xfs, btrfs, apfs)
PATH_MAX_BYTES = 4096


def _out_path(given: str | None, name: str, prefix: str = "") -> Path:
    """The output folder: ``--out`` if given (checked), else ``out/PREFIX+NAME``.

    The default never leaves :data:`OUT_ROOT`: ``name`` was validated by the scenario or sweep
    (a safe character set), and the resolved path is checked to be a folder inside the root.
    """
    if given is not None:
        if not given.strip():
            raise ConfigError("--out", "is empty: give a folder (or leave --out out)")
        out = Path(given)
    else:
        root = OUT_ROOT.resolve()
        out = OUT_ROOT / f"{prefix}{name}"
        inside = out.resolve()
        if inside == root or root not in inside.parents:
            raise ConfigError("name", f"{name!r} does not name a folder inside {OUT_ROOT}/")
    for part in out.parts:
        if len(os.fsencode(part)) > NAME_MAX_BYTES:
            raise ConfigError(
                "--out", f"a part of the path is longer than {NAME_MAX_BYTES} bytes: {part[:40]}..."
            )
    if len(os.fsencode(str(out.absolute()))) > PATH_MAX_BYTES:
        raise ConfigError("--out", f"the path is longer than {PATH_MAX_BYTES} bytes")
    return out


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # argparse's own errors: one line, exit 2, like ours
        self.print_usage(sys.stderr)
        print(f"imdrive: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


def _cmd_presets(args) -> int:
    from imdrive.config.machine import machine_presets
    from imdrive.config.presets import preset_names
    from imdrive.config.scenario import Scenario

    print("scenario presets:")
    for name in preset_names():
        sc = Scenario.read(name)
        print(f"  {name:<22} {sc.description}")
    print("machine parameter sets ([machine] preset = ...):")
    for name, desc in machine_presets().items():
        print(f"  {name:<22} {desc}")
    return EXIT_OK


def _cmd_show(args) -> int:
    from imdrive.config.machine import machine_preset, machine_presets, rated_point_comment
    from imdrive.config.presets import preset_names, preset_text

    if args.preset not in preset_names() and args.preset in machine_presets():
        # a machine parameter set (listed by 'imdrive presets' beside the scenarios)
        from imdrive.config.toml_writer import dumps

        m = machine_preset(args.preset)
        values = {k: v for k, v in m.to_dict().items() if k != "description"}
        sys.stdout.write(
            f"# machine parameter set {args.preset!r}: {m.description}\n"
            f"# a scenario uses it with [machine] preset = {args.preset!r} (any key below may be\n"
            "# overridden in that section); these are its values\n"
            + dumps({"machine": {"preset": args.preset, **values}})
            + rated_point_comment(m)
        )
        return EXIT_OK
    if args.all:
        from imdrive.config.scenario import Scenario

        scenario = Scenario.read(args.preset)
        sys.stdout.write(scenario.to_toml() + "\n" + rated_point_comment(scenario.machine))
    else:
        sys.stdout.write(preset_text(args.preset))
    return EXIT_OK


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


def _cmd_run(args) -> int:
    from imdrive.config.scenario import Scenario
    from imdrive.run.build import build_arrays
    from imdrive.run.result import check_result_folder
    from imdrive.run.simulate import kernels_cached, simulate

    scenario = Scenario.read(args.scenario, args.set or [])
    out = _out_path(args.out, _run_folder_name(args.scenario))
    check_result_folder(out, args.force)
    arrays = build_arrays(scenario)  # every derived quantity checked before anything runs
    if not args.quiet:
        if not kernels_cached():
            print("imdrive: compiling the kernels (first run only) ...", file=sys.stderr)
        print(
            f"imdrive: running {scenario.name} ({scenario.simulation.t_end_s:g} s) ...",
            file=sys.stderr,
        )
    res = simulate(scenario, arrays)
    res.save(out, force=args.force)
    s = res.summary()
    if res.diverged:
        print(
            f"imdrive: error: {res.divergence_message}; partial results in {out}", file=sys.stderr
        )
        return EXIT_DIVERGED
    if res.lost_control:
        print(f"imdrive: error: {res.lost_control_message}; results in {out}", file=sys.stderr)
        return EXIT_LOST_CONTROL
    if not args.quiet:
        fin = s["final"]
        print(
            f"imdrive: done in {time.perf_counter() - args.t0:.1f} s (simulation "
            f"{res.wall_time_s:.3f} s, {s['real_time_factor']:.0f}x real time); final speed "
            f"{fin['speed_rpm']:.2f} rpm, torque {fin['torque_Nm']:.3f} N m -> {out}",
            file=sys.stderr,
        )
    return EXIT_OK


def _cmd_fuzzy_table(args) -> int:
    from imdrive.fuzzy import format_table, fuzzy_table, table_diff

    if args.diff:
        paper = fuzzy_table("paper")
        rules = fuzzy_table("rules")
        diff = table_diff(rules, paper)
        if args.format == "csv":
            print("E,DE,rules,paper")
            for e, de, a, b in diff:
                print(f"{e},{de},{a},{b}")
        else:
            print(f"{len(diff)} of 169 cells differ (rule-compiled vs printed Table III):")
            print(f"  {'E':>3} {'DE':>3} {'rules':>6} {'paper':>6}")
            for e, de, a, b in diff:
                print(f"  {e:>3} {de:>3} {a:>6} {b:>6}")
        return EXIT_OK
    sys.stdout.write(format_table(fuzzy_table(args.source), args.format))
    if args.format == "text":
        sys.stdout.write("\n")
    return EXIT_OK


def _cmd_paper(args) -> int:
    from imdrive.studies.paper import run_all

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError("--out", f"{out} exists and is not a folder")
    t0 = time.perf_counter()
    res = run_all(out)
    n_png = len(list(out.glob("*.png")))
    print(
        f"imdrive: paper reproduction done in {time.perf_counter() - t0:.0f} s: {n_png} figures, "
        f"tables and results.json in {out}",
        file=sys.stderr,
    )
    for row in res["compensation"]:
        t = row["time_to_tolerance_s"]
        print(
            f"  {row['preset']:<24} R2_hat {row['R2_est_initial_ohm']:.4f} -> "
            f"{row['R2_est_final_ohm']:.4f} ohm ({row['R2_est_final_error_pct']:+.1f} %), "
            f"within 2 %: {'never' if t is None else f'{t:.1f} s'}, speed error "
            f"{row['speed_error_before_rpm']:+.2f} -> {row['speed_error_after_rpm']:+.2f} rpm",
            file=sys.stderr,
        )
    return EXIT_OK


def _cmd_sweep(args) -> int:
    from imdrive.sweep import load_sweep, run_sweep, sweep_names, sweep_text

    if args.list:
        for n in sweep_names():
            text, _ = sweep_text(n)
            desc = tomllib.loads(text).get("description", "")
            print(f"  {n:<22} {desc}")
        return EXIT_OK
    if not args.sweep:
        raise ConfigError("sweep", "name a built-in sweep (see --list) or a sweep file")
    if args.show:
        sys.stdout.write(sweep_text(args.sweep)[0])
        return EXIT_OK
    if args.chunk_size is not None and args.chunk_size < 1:
        raise ConfigError("--chunk-size", f"must be >= 1 (got {args.chunk_size})")
    sweep = load_sweep(args.sweep, max_runs=args.max_runs)
    out = _out_path(args.out, sweep.name, "sweep-")
    cs = args.chunk_size or sweep.chunk_size
    val = sweep.validation
    if args.dry_run:
        print(
            f"sweep {sweep.name}: {sweep.n_runs} runs "
            f"({' x '.join(str(n) for n in sweep.shape) if not sweep.random else 'random'}), "
            f"{sweep.n_chunks(cs)} chunks of {cs}, axes: {', '.join(a.name for a in sweep.axes)}"
        )
        print(
            f"validated: {val.get('checked', 0)} distinct scenarios"
            + (
                ""
                if val.get("complete", True)
                else " (each axis value alone; the combinations are checked as they run)"
            )
        )
    if val.get("n_failing"):
        print(
            f"imdrive: {val['n_failing']} combination(s) of axis values cannot run and will be "
            f"recorded as failed, e.g. {val['failing'][0][0]}: {val['failing'][0][1]}",
            file=sys.stderr,
        )
    if args.dry_run:
        return EXIT_OK
    t0 = time.perf_counter()
    df = run_sweep(
        sweep,
        out,
        scheduler=args.scheduler,
        resume=args.resume,
        chunk_size=args.chunk_size,
        figures=not args.no_figures,
        report=not args.no_report,
        progress=None if not args.quiet else False,
    )
    if not args.quiet:
        n_div = int(df["diverged"].sum())
        n_fail = int((df["status"] < 0).sum())
        n_lc = int(df["lost_control"].sum()) if "lost_control" in df else 0
        print(
            f"imdrive: sweep {sweep.name}: {len(df)} runs ({n_div} diverged, {n_lc} lost "
            f"control, {n_fail} failed) in "
            f"{time.perf_counter() - t0:.1f} s -> {out / 'runs.parquet'}",
            file=sys.stderr,
        )
    # diverged runs are results of the sweep (recorded in the table), not a failure
    return EXIT_OK


def _cmd_bench_estimators(args) -> int:
    from imdrive.bench.report import bench_estimators

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError("--out", f"{out} exists and is not a folder")
    t0 = time.perf_counter()
    s = bench_estimators(out, quick=args.quick)
    if not args.quiet:
        print(
            f"imdrive: bench-estimators: {s['runs']} runs in {time.perf_counter() - t0:.1f} s "
            f"(kernels {s['wall_s']:.1f} s) -> {s['csv']}, {s['markdown']}",
            file=sys.stderr,
        )
    return EXIT_OK


def _parse_range(text: str, name: str):
    """``MIN:MAX:N`` -> N evenly spaced values (one-line ConfigError otherwise)."""
    import numpy as np

    rule = f"expected MIN:MAX:N with finite MIN < MAX and integer N >= 2 (got {text!r})"
    parts = text.split(":")
    if len(parts) != 3:
        raise ConfigError(name, rule)
    try:
        lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise ConfigError(name, rule) from None
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi and n >= 2):
        raise ConfigError(name, rule)
    if n > 1000:
        raise ConfigError(name, f"at most 1000 points per axis (got {n})")
    return np.linspace(lo, hi, n)


def _parse_ratios(text: str | None, name: str) -> list[float]:
    if not text:
        return []
    out = []
    for part in text.split(","):
        try:
            v = float(part)
        except ValueError:
            raise ConfigError(
                name, f"expected comma-separated numbers > 0 (got {text!r})"
            ) from None
        if not (v > 0 and v < float("inf")):
            raise ConfigError(name, f"ratios must be finite and > 0 (got {part!r})")
        out.append(v)
    return out


def _cmd_stability(args) -> int:
    import pandas as pd

    from imdrive.config.scenario import Scenario

    speeds = _parse_range(args.speeds, "--speeds")
    torques = _parse_range(args.torques, "--torques")
    r1 = _parse_ratios(args.R1_ratios, "--r1-ratios")
    r2 = _parse_ratios(args.R2_ratios, "--r2-ratios")
    scenario = Scenario.read(args.scenario, args.set or [])
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ConfigError("--out", f"{out} exists and is not a folder")

    from imdrive.stability.maps import stability_map
    from imdrive.stability.plots import plot_map, plot_overlay

    t0 = time.perf_counter()
    base = stability_map(scenario, speeds, torques)
    frames = [base.assign(map="base")]
    over_r1 = {
        f"R1_hat/R1 = {r:g}": stability_map(scenario, speeds, torques, R1_ratio=r) for r in r1
    }
    over_r2 = {
        f"R2_hat/R2 = {r:g}": stability_map(scenario, speeds, torques, R2_ratio=r) for r in r2
    }
    for label, df in {**over_r1, **over_r2}.items():
        frames.append(df.assign(map=label))
    wall = time.perf_counter() - t0
    out.mkdir(parents=True, exist_ok=True)
    pd.concat(frames, ignore_index=True).to_csv(out / "stability.csv", index=False)
    plot_map(base, out / "stability.png", title=f"{scenario.name}: small-signal stability")
    if over_r1:
        plot_overlay({"as configured": base, **over_r1}, out / "stability_R1.png")
    if over_r2:
        plot_overlay({"as configured": base, **over_r2}, out / "stability_R2.png")
    if not args.quiet:
        ok = base["status"] == "ok"
        print(
            f"imdrive: stability of {scenario.name}: {len(base)} points in {wall:.2f} s, "
            f"{int(base['stable'].sum())} stable, {int(ok.sum() - base['stable'].sum())} unstable, "
            f"{int((~ok).sum())} without steady state -> {out / 'stability.csv'}",
            file=sys.stderr,
        )
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="imdrive",
        description="Simulate sensorless induction-motor drives.",
        epilog=_examples(
            "imdrive presets",
            "imdrive run sensorless",
            "imdrive show sensorless > my.toml; imdrive run my.toml",
            "imdrive sweep detuning-map",
            "imdrive <command> --help",
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=_version())
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    r = sub.add_parser(
        "run",
        help="run a preset or scenario file",
        description="Run one drive: a built-in preset by name, a scenario TOML file, or a "
        "run's summary.json (to run it again). Writes timeseries.csv, summary.json, PNG figures "
        "and report.html (interactive; open it in a browser) into out/PRESET, or out/FILE for a "
        "file named FILE.toml, unless --out says otherwise. Exit codes: imdrive --help.",
        epilog=_examples(
            "imdrive run sensorless",
            "imdrive run sensorless --set simulation.t_end_s=2 --set load.torque_Nm=6",
            "imdrive run my.toml --out results/my-run",
            "imdrive run out/sensorless/summary.json",
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
        "--force",
        action="store_true",
        help="replace an --out folder that holds files other than an imdrive result",
    )
    r.add_argument("-q", "--quiet", action="store_true")
    r.set_defaults(func=_cmd_run)

    ps = sub.add_parser(
        "presets",
        help="list the built-in presets",
        description="List the built-in scenario presets and machine parameter sets.",
        epilog=_examples("imdrive presets"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ps.set_defaults(func=_cmd_presets)

    sh = sub.add_parser(
        "show",
        help="print a preset's TOML, to copy and edit",
        description="Print a preset's TOML file, or with --all every key of the scenario with "
        "its value (the defaults filled in).",
        epilog=_examples(
            "imdrive show sensorless > my.toml", "imdrive show sensorless --all | less"
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sh.add_argument("preset")
    sh.add_argument(
        "--all", action="store_true", help="every key with its value, defaults included"
    )
    sh.set_defaults(func=_cmd_show)

    pp = sub.add_parser(
        "paper",
        help="regenerate every figure and table of the reproduction",
        description="Run the paper's figures and the compensation study; write the figures, "
        "tables and results.json (docs/paper.md explains them).",
        epilog=_examples("imdrive paper", "imdrive paper --out results/paper"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    pp.add_argument("--out", metavar="DIR", default="out/paper")
    pp.set_defaults(func=_cmd_paper)

    ft = sub.add_parser(
        "fuzzy-table",
        help="print the compensator's 13x13 lookup table",
        description="Print the fuzzy compensator's 13x13 lookup table (the paper's Table III, "
        "or the one compiled from the fitted rules), or where the two differ.",
        epilog=_examples(
            "imdrive fuzzy-table",
            "imdrive fuzzy-table --source rules --format csv",
            "imdrive fuzzy-table --diff",
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ft.add_argument(
        "--source",
        choices=("paper", "rules"),
        default="paper",
        help="the printed Table III, or the table compiled from the fitted rules",
    )
    ft.add_argument("--format", choices=("text", "csv"), default="text")
    ft.add_argument(
        "--diff",
        action="store_true",
        help="list the cells where the rule-compiled table differs from the printed one",
    )
    ft.set_defaults(func=_cmd_fuzzy_table)

    sw = sub.add_parser(
        "sweep",
        help="run a parameter sweep into a Parquet store",
        description="Run a sweep (a built-in one by name, or a sweep TOML file): a Parquet "
        "table of summary metrics, one row per run, heatmap figures and report.html (the "
        "heatmaps with hover values).",
        epilog=_examples(
            "imdrive sweep --list",
            "imdrive sweep detuning-map --dry-run",
            "imdrive sweep detuning-map",
            "imdrive sweep my-sweep.toml --out results/sweep --resume",
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sw.add_argument("sweep", nargs="?", metavar="SWEEP_OR_FILE")
    sw.add_argument("--out", metavar="STORE", help="store folder (default out/sweep-NAME)")
    sw.add_argument("--scheduler", metavar="ADDRESS", help="dask.distributed scheduler address")
    sw.add_argument("--resume", action="store_true", help="continue an interrupted sweep")
    sw.add_argument("--chunk-size", type=int, metavar="N", help="runs per chunk (default 32)")
    sw.add_argument("--no-figures", action="store_true", help="skip the heatmap PNGs")
    sw.add_argument(
        "--no-report", action="store_true", help="skip report.html (the interactive heatmaps)"
    )
    sw.add_argument("--dry-run", action="store_true", help="validate, print the size, run nothing")
    sw.add_argument(
        "--max-runs",
        type=int,
        default=None,
        metavar="N",
        help="refuse a sweep of more runs (default 10000000)",
    )
    sw.add_argument("--list", action="store_true", help="list the built-in sweeps")
    sw.add_argument("--show", action="store_true", help="print the sweep file")
    sw.add_argument("-q", "--quiet", action="store_true")
    sw.set_defaults(func=_cmd_sweep)

    st = sub.add_parser(
        "stability",
        help="small-signal stability map over speed x load torque",
        description="Solve the closed loop's steady state and its discrete small-signal model "
        "at every point of a speed x torque grid; write stability.csv and heatmap PNGs.",
        epilog=_examples(
            "imdrive stability sensorless --out out/stability",
            "imdrive stability sensorless --speeds 0:300:31 --torques=-12:12:25 "
            "--r2-ratios 0.8,1.2 --out out/stability-low",
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    st.add_argument("scenario", metavar="PRESET_OR_FILE")
    st.add_argument(
        "--set", action="append", metavar="KEY.PATH=VALUE", help="override (repeatable)"
    )
    st.add_argument("--speeds", default="0:1500:50", metavar="MIN:MAX:N", help="speed refs, rpm")
    st.add_argument(
        "--torques",
        default="-24:24:40",
        metavar="MIN:MAX:N",
        help="load torques, N m (write --torques=-24:24:40 for a negative start)",
    )
    st.add_argument(
        "--r1-ratios", dest="R1_ratios", metavar="A,B,...", help="overlay maps for R1_hat/R1"
    )
    st.add_argument(
        "--r2-ratios", dest="R2_ratios", metavar="A,B,...", help="overlay maps for R2_hat/R2"
    )
    st.add_argument("--out", metavar="DIR", required=True)
    st.add_argument("-q", "--quiet", action="store_true")
    st.set_defaults(func=_cmd_stability)

    be = sub.add_parser(
        "bench-estimators",
        help="run the estimator test protocol: CSV, a figure per metric, a Markdown table",
        description="Every speed estimator and R2 adaptation method on the same scenarios "
        "(average and realistic drive) and metrics (docs/estimators.md): estimators.csv, "
        "<metric>.png and estimators.md in DIR.",
        epilog=_examples("imdrive bench-estimators --quick --out out/bench"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    be.add_argument("--quick", action="store_true", help="a small subset (CI)")
    be.add_argument("--out", metavar="DIR", required=True)
    be.add_argument("-q", "--quiet", action="store_true")
    be.set_defaults(func=_cmd_bench_estimators)
    _add_machine_from_nameplate(sub)
    return p


def _cmd_machine_from_nameplate(args) -> int:
    from imdrive.analysis.nameplate import machine_from_nameplate_command

    return machine_from_nameplate_command(args)


def _add_machine_from_nameplate(sub) -> None:
    mn = sub.add_parser(
        "machine-from-nameplate",
        help="estimate a machine's equivalent circuit from its nameplate (a TOML file)",
        description="Estimate the T-equivalent circuit from nameplate and catalogue data "
        "(imdrive.analysis.nameplate: method, assumptions) and write a [machine] TOML file "
        'for a scenario\'s [machine] file = "...".',
        epilog=_examples(
            "imdrive machine-from-nameplate --power-kw 2.2 --voltage 400 --frequency 50 "
            "--poles 4 --speed 1436 --current 5 --pf 0.79 --efficiency 0.82 "
            "--breakdown-ratio 2.9 --out my-motor.toml"
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    for flag, dest, kind, text in (
        ("--power-kw", "power_kW", float, "rated shaft power, kW"),
        ("--voltage", "voltage", float, "rated line-to-line voltage, V rms"),
        ("--frequency", "frequency", float, "rated frequency, Hz"),
        ("--poles", "poles", int, "number of poles (4 for 1500/1800 rpm machines)"),
        ("--speed", "speed", float, "rated speed, rpm"),
        ("--current", "current", float, "rated line current, A rms"),
        ("--pf", "pf", float, "rated power factor (0-1)"),
        ("--efficiency", "efficiency", float, "rated efficiency (0-1, not %)"),
    ):
        mn.add_argument(flag, dest=dest, type=kind, required=True, help=text)
    mn.add_argument("--breakdown-ratio", type=float, help="breakdown torque / rated torque")
    mn.add_argument("--starting-current-ratio", type=float, help="locked-rotor / rated current")
    mn.add_argument(
        "--design",
        choices=("A", "B", "C", "D", "wound"),
        default="A",
        help="NEMA design letter: the X1/X2 split (IEEE Std 112); default A (1:1)",
    )
    mn.add_argument("--J", type=float, help="rotor inertia, kg m^2 (default: H = 0.5 s)")
    mn.add_argument("--description", help="text for the machine's description")
    mn.add_argument("--out", metavar="FILE", help="write the TOML here (default: stdout)")
    mn.set_defaults(func=_cmd_machine_from_nameplate)


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """A :class:`~imdrive.errors.ConfigWarning` as one line ``imdrive: warning: field: rule``;
    other warnings as Python prints them."""
    if issubclass(category, ConfigWarning):
        print(f"imdrive: warning: {message}", file=sys.stderr)
    else:
        print(warnings.formatwarning(message, category, filename, lineno, line), file=sys.stderr)


def _examples(*lines: str) -> str:
    """An ``examples:`` block for the end of a --help text."""
    return "examples:\n" + "\n".join(f"  {line}" for line in lines)


def _version() -> str:
    from imdrive import __version__

    return f"imdrive {__version__}"


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    args.t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.showwarning = _show_warning
            return args.func(args)
    except ConfigError as exc:
        return _fail(f"{exc}{_did_you_mean(exc, args)}", EXIT_BAD_INPUT)
    except EnvironmentFailure as exc:
        return _fail(exc.cause, EXIT_ENVIRONMENT)
    except MemoryError:
        return _fail("out of memory (a smaller sweep, chunk or log_every?)", EXIT_ENVIRONMENT)
    except OSError as exc:
        return _fail(describe_os_error(exc), EXIT_ENVIRONMENT)
    except KeyboardInterrupt:
        print("imdrive: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        if os.environ.get("IMDRIVE_DEBUG"):
            raise
        msg = str(exc).splitlines()[0][:300] if str(exc) else ""
        return _fail(
            f"internal error ({type(exc).__name__}: {msg}); set IMDRIVE_DEBUG=1 for the traceback",
            EXIT_INTERNAL,
        )


def _did_you_mean(exc: ConfigError, args) -> str:
    """``"; did you mean 'X'?"`` for a mistyped key, preset or sweep name (difflib), else ``""``.

    Appended by the command line only: the library's messages stay as they are.
    """
    import difflib

    rule = exc.rule
    given, names, cutoff = None, [], 0.6
    if rule.startswith(("unknown key", "no such setting")):
        from imdrive.config.schema import setting_paths

        paths = setting_paths()
        given = exc.field
        names = sorted({".".join(p) for p in paths} | {p[0] for p in paths})
        cutoff = 0.75
    elif exc.field in ("preset", "scenario") and (
        "unknown preset" in rule or "neither a preset" in rule
    ):
        from imdrive.config.presets import preset_names

        given = getattr(args, "scenario", None) or getattr(args, "preset", None)
        names = preset_names()
    elif exc.field == "sweep" and "neither a built-in sweep" in rule:
        from imdrive.sweep import sweep_names

        given, names = getattr(args, "sweep", None), sweep_names()
    if not given or not names:
        return ""
    match = difflib.get_close_matches(str(given), names, n=1, cutoff=cutoff)
    return f"; did you mean {match[0]!r}?" if match and match[0] != given else ""


def _fail(message: str, code: int) -> int:
    """Print one line on stderr and return the exit code."""
    print(f"imdrive: error: {message}", file=sys.stderr)
    return code


if __name__ == "__main__":
    raise SystemExit(main())
