"""``imdrive commission``: the identification run of a drive (self-commissioning)."""

from __future__ import annotations

import argparse
import sys

from imdrive.cli._common import (
    EXIT_NOT_IDENTIFIED,
    EXIT_OK,
    _examples,
    add_allow_plugins,
    add_force,
    output_folder,
)


def _cmd_commission(args) -> int:
    from imdrive.commission import CommissioningFailed, commission
    from imdrive.commission.identify import owns_commission_file
    from imdrive.config.scenario import Scenario

    sc = Scenario.read(args.scenario, args.set or [])
    # the folder rule of every command, before the identification run starts
    out = output_folder(
        args.out, owns=owns_commission_file, force=args.force, what="a commissioning result"
    )
    from imdrive.commission.base import switched_off

    if not args.quiet:  # one line per setting the tests run without
        for line in switched_off(sc):
            print(f"switched off for the tests: {line}")
    try:
        res = commission(sc, out, force=args.force)
    except CommissioningFailed as exc:
        print(f"imdrive: commissioning failed: {exc}", file=sys.stderr)
        return EXIT_NOT_IDENTIFIED
    if args.quiet:  # as run -q: no compile notice, no summary; warnings and errors still shown
        return EXIT_OK
    for key, err in res.relative_error.items():
        text = "-" if err is None else f"{100 * err:+7.2f} %"
        print(f"{key:12s} {text}")
    print(f"wrote {out}/summary.json, identified.toml and the figures ({res.wall_s:.1f} s)")
    return EXIT_OK


def add_parser(sub) -> None:
    """Register ``commission`` on the sub-command parser ``sub``."""
    p = sub.add_parser(
        "commission",
        help="identify the machine and inverter of a scenario (identification run)",
        description="Run the standstill DC, rotating no-load, standstill AC and acceleration "
        "tests on the simulated drive and write DIR/summary.json (identified and true values), "
        "DIR/identified.toml (the scenario with the identified controller model) and figures. "
        f"A test that does not converge exits {EXIT_NOT_IDENTIFIED}, writing nothing.",
        epilog=_examples("imdrive commission sensorless-realistic --out out/commission"),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scenario", help="preset name or scenario file")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    add_force(p, "a commissioning result")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a setting")
    p.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="print no compile notice and no result table (as run -q); warnings and errors "
        "are still printed",
    )
    add_allow_plugins(p)
    p.set_defaults(func=_cmd_commission)
