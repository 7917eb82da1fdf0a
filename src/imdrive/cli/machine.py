"""``imdrive machine-from-nameplate``: a machine's equivalent circuit from its nameplate."""

from __future__ import annotations

import argparse

from imdrive.cli._common import _examples


def _cmd_machine_from_nameplate(args) -> int:
    # imported here: the estimate loads scipy, which every other command's start can skip
    from imdrive.analysis.nameplate_cli import machine_from_nameplate_command

    return machine_from_nameplate_command(args)


def add_parser(sub) -> None:
    """Register ``machine-from-nameplate`` on the sub-command parser ``sub``."""
    mn = sub.add_parser(
        "machine-from-nameplate",
        help="estimate a machine's equivalent circuit from its nameplate (a TOML file)",
        description="Estimate the T-equivalent circuit from nameplate and catalogue data "
        "(imdrive.analysis.nameplate: methods, assumptions) and write a [machine] TOML file "
        'for a scenario\'s [machine] file = "...".',
        epilog=_examples(
            "imdrive machine-from-nameplate --power-kw 2.2 --voltage 400 --frequency 50 "
            "--poles 4 --speed 1436 --current 5 --pf 0.79 --efficiency 0.82 "
            "--starting-current-ratio 6 --out my-motor.toml",
            "imdrive machine-from-nameplate --power-kw 2.2 --voltage 400 --frequency 50 "
            "--poles 4 --speed 1436 --current 5 --pf 0.79 --efficiency 0.82 "
            "--breakdown-ratio 2.9 --starting-current-ratio 7 --out my-motor.toml",
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
        ("--efficiency", "efficiency", float, "rated efficiency (0-1, not %%)"),
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
    mn.add_argument(
        "--method",
        choices=("catalogue", "lee", "fit"),
        help="catalogue (the default): every figure given, R1 the stator's, the leakage from "
        "the breakdown torque when given, else from the starting current or code letter; lee "
        "(deprecated): the nameplate-only method of Lee, Frank, Sen et al. (NAPS 2012); fit "
        "(deprecated): least squares with every loss in R1",
    )
    mn.add_argument(
        "--code-letter",
        help="NEMA code letter (locked-rotor kVA/hp), used without --breakdown-ratio and "
        "--starting-current-ratio (default: G assumed)",
    )
    for flag, text in (
        ("--core-loss-fraction", "core loss / total loss (default 0.12)"),
        ("--mechanical-loss-fraction", "friction and windage / total loss (default 0.14)"),
        ("--stray-loss-fraction", "stray-load loss / rated power (default IEEE Std 112's)"),
    ):
        mn.add_argument(flag, type=float, help=text)
    mn.add_argument(
        "--J", type=float, help="rotor inertia, kg m^2 (default: that of a rotor of this size)"
    )
    mn.add_argument("--description", help="text for the machine's description")
    mn.add_argument("--out", metavar="FILE", help="write the TOML here (default: stdout)")
    mn.set_defaults(func=_cmd_machine_from_nameplate)
