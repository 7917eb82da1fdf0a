"""``imdrive bench-estimators``: the estimator test protocol."""

from __future__ import annotations

import argparse
import sys
import time

from imdrive.cli._common import EXIT_OK, _examples, add_force, output_folder


def _owns_bench_file(name: str) -> bool:
    """The files ``imdrive bench-estimators`` writes: estimators.csv, estimators.md, PNGs."""
    return name in ("estimators.csv", "estimators.md") or name.endswith(".png")


def _cmd_bench_estimators(args) -> int:
    from imdrive.bench.report import bench_estimators

    out = output_folder(
        args.out, owns=_owns_bench_file, force=args.force, what="an estimator benchmark"
    )
    t0 = time.perf_counter()
    s = bench_estimators(out, quick=args.quick)
    if not args.quiet:
        print(
            f"imdrive: bench-estimators: {s['runs']} runs in {time.perf_counter() - t0:.1f} s "
            f"(kernels {s['wall_s']:.1f} s) -> {s['csv']}, {s['markdown']}",
            file=sys.stderr,
        )
    return EXIT_OK


def add_parser(sub) -> None:
    """Register ``imdrive bench-estimators``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``imdrive`` parser's sub-commands.
    """
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
    add_force(be, "an estimator benchmark")
    be.add_argument("-q", "--quiet", action="store_true")
    be.set_defaults(func=_cmd_bench_estimators)
