"""``imdrive sweep``: a parameter sweep into a Parquet store."""

from __future__ import annotations

import argparse
import sys
import time
import tomllib

from imdrive.cli._common import EXIT_OK, _examples, add_allow_plugins, output_folder
from imdrive.errors import ConfigError


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
    out = output_folder(args.out, sweep.name, "sweep-")  # the store: a manifest of this sweep
    cs = args.chunk_size or sweep.chunk_size
    val = sweep.validation
    if args.dry_run:
        print(
            f"sweep {sweep.name}: {sweep.n_runs} runs "
            f"({' x '.join(str(n) for n in sweep.shape) if not sweep.random else 'random'}), "
            f"{sweep.n_chunks(cs)} chunks of {cs}, axes: {', '.join(a.name for a in sweep.axes)}"
        )
        from imdrive.config.plugins import looked_past

        if looked_past():
            print(
                "plug-in modules, not imported (a dry run runs none of their code; their "
                f"estimator's settings are unchecked): {', '.join(looked_past())}"
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
        connect_timeout_s=args.connect_timeout,
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
        from imdrive.run.status import verdict_counts

        print(
            f"imdrive: sweep {sweep.name}: {len(df)} runs ({n_div} diverged, {n_lc} lost "
            f"control, {n_fail} failed) in "
            f"{time.perf_counter() - t0:.1f} s -> {out / 'runs.parquet'}; status: "
            f"{verdict_counts(df)}",
            file=sys.stderr,
        )
    # diverged runs are results of the sweep (recorded in the table), not a failure
    return EXIT_OK


def add_parser(sub) -> None:
    """Register ``imdrive sweep``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``imdrive`` parser's sub-commands.
    """
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
    sw.add_argument(
        "--connect-timeout",
        type=float,
        default=10.0,
        metavar="S",
        help="seconds the scheduler has to answer and greet (default 10)",
    )
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
    add_allow_plugins(sw)
    sw.set_defaults(func=_cmd_sweep)
