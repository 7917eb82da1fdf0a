"""``imdrive compare``: several result folders side by side."""

from __future__ import annotations

import argparse
import sys

from imdrive.cli._common import EXIT_OK, _examples, add_force, output_folder


def _owns_compare_file(name: str) -> bool:
    """The files ``imdrive compare`` writes: compare.png, metrics.csv, report.html."""
    return name in ("compare.png", "metrics.csv", "report.html")


def _cmd_compare(args) -> int:
    from imdrive.run.compare import compare

    signals = [s.strip() for s in args.signals.split(",") if s.strip()] if args.signals else None
    out = output_folder(  # checked before the runs are read: the one rule of every writer
        args.out, "compare", owns=_owns_compare_file, force=args.force, what="a comparison"
    )
    cmp = compare(args.runs, signals=signals)
    paths = cmp.save(out)
    from imdrive.config.plugins import looked_past

    if looked_past():  # compare only looks: a run's plug-in modules are named, never imported
        print(
            "imdrive: note: plug-in modules of the runs, not imported (comparing runs none of "
            f"their code): {', '.join(looked_past())}",
            file=sys.stderr,
        )
    if not args.quiet:
        print(
            f"imdrive: compared {len(cmp.runs)} runs -> " + ", ".join(str(p) for p in paths),
            file=sys.stderr,
        )
    return EXIT_OK


def add_parser(sub) -> None:
    """Register ``imdrive compare``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``imdrive`` parser's sub-commands.
    """
    c = sub.add_parser(
        "compare",
        help="several runs side by side: overlaid signals, metrics, an HTML report",
        description="Overlay the signals of result folders (written by imdrive run) and put "
        "their metrics side by side: compare.png, metrics.csv and report.html (linked zoomable "
        "panels, each with its time axis) in DIR (default out/compare).",
        epilog=_examples(
            "imdrive run sensorless; imdrive run sensorless-realistic",
            "imdrive compare out/sensorless out/sensorless-realistic --out out/cmp",
            "imdrive compare out/a out/b --signals speed_rpm,speed_est_rpm,e_d0_Wb",
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    c.add_argument("runs", nargs="+", metavar="RUN_DIR")
    c.add_argument("--out", metavar="DIR")
    add_force(c, "a comparison")
    c.add_argument("--signals", metavar="COL,...", help="columns to overlay, a panel each")
    c.add_argument("-q", "--quiet", action="store_true")
    c.set_defaults(func=_cmd_compare)
