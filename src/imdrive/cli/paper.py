"""``imdrive paper``: every figure and table of the paper's reproduction."""

from __future__ import annotations

import argparse
import sys
import time

from imdrive.cli._common import EXIT_OK, _examples, add_force, output_folder


def _owns_paper_file(name: str) -> bool:
    """The files ``imdrive paper`` writes: figures, tables (CSV) and results.json."""
    return name == "results.json" or name.endswith((".png", ".csv"))


def _cmd_paper(args) -> int:
    from imdrive.studies.paper import run_all

    out = output_folder(
        args.out, owns=_owns_paper_file, force=args.force, what="the paper's reproduction"
    )
    t0 = time.perf_counter()
    res = run_all(out, progress=(lambda msg: None) if args.quiet else None)
    if args.quiet:  # the files say it all; errors still go to stderr
        return EXIT_OK
    n_png = len(list(out.glob("*.png")))
    print(
        f"imdrive: paper reproduction done in {time.perf_counter() - t0:.0f} s: {n_png} figures, "
        f"tables and results.json in {out}",
        file=sys.stderr,
    )
    for row in res["compensation"]:
        t = row["time_to_tolerance_s"]
        print(
            f"  {row['preset']:<24} R2_hat {row['R2_hat_initial_ohm']:.4f} -> "
            f"{row['R2_hat_final_ohm']:.4f} ohm ({row['R2_hat_final_error_pct']:+.1f} %), "
            f"within 2 %: {'never' if t is None else f'{t:.1f} s'}, speed error "
            f"{row['speed_error_before_rpm']:+.2f} -> {row['speed_error_after_rpm']:+.2f} rpm",
            file=sys.stderr,
        )
    return EXIT_OK


def add_parser(sub) -> None:
    """Register ``imdrive paper``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``imdrive`` parser's sub-commands.
    """
    pp = sub.add_parser(
        "paper",
        help="regenerate every figure and table of the reproduction",
        description="Run the paper's figures and the compensation study; write the figures, "
        "tables and results.json (docs/paper.md explains them).",
        epilog=_examples("imdrive paper", "imdrive paper --out results/paper"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    pp.add_argument("--out", metavar="DIR", default="out/paper")
    add_force(pp, "the paper's reproduction")
    pp.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="print nothing but errors (no compile notice, no summary), as run and sweep",
    )
    pp.set_defaults(func=_cmd_paper)
