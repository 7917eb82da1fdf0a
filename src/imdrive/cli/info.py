"""``imdrive presets``, ``imdrive show`` and ``imdrive fuzzy-table``: what is built in."""

from __future__ import annotations

import argparse
import sys

from imdrive.cli._common import EXIT_OK, _examples


def _cmd_presets(args) -> int:
    from imdrive.config.machine import machine_presets
    from imdrive.config.presets import preset_names
    from imdrive.config.scenario import Scenario
    from imdrive.sweep import sweep_names
    from imdrive.sweep.spec import sweep_description

    groups = {
        "scenario presets (imdrive run NAME):": {
            name: (Scenario.read(name).description or "") for name in preset_names()
        },
        "sweep presets (imdrive sweep NAME):": {
            name: sweep_description(name) for name in sweep_names()
        },
        "machine parameter sets ([machine] preset = NAME):": dict(machine_presets()),
    }
    width = max(len(n) for g in groups.values() for n in g) + 2
    for title, items in groups.items():
        print(title)
        for name, desc in items.items():
            print(f"  {name:<{width}}{' '.join(str(desc).split())}")
    return EXIT_OK


def _mode_comment(scenario) -> str:
    """The first line of ``imdrive show``: how the scenario drives the machine."""
    if scenario.drive.mode == "vector":
        return f"# drive mode: vector (speed feedback {scenario.control.speed_feedback})\n"
    return (
        '# drive mode: open-loop (no [drive] mode = "vector": the machine runs on the\n'
        "# [open_loop] voltage; [control], [estimator] and [compensator] are not used)\n"
    )


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
    from imdrive.config.plugins import looking
    from imdrive.config.scenario import Scenario

    with looking() as skipped:  # looking at a file never runs its plug-in modules
        scenario = Scenario.read(args.preset)
    if args.all:
        text = scenario.to_toml() + "\n" + rated_point_comment(scenario.machine)
    elif args.preset in preset_names():
        text = preset_text(args.preset)
    else:  # a scenario file of one's own: as it is
        from imdrive.config.presets import scenario_text

        text = scenario_text(args.preset)
    sys.stdout.write(_mode_comment(scenario) + _plugins_comment(skipped) + text)
    return EXIT_OK


def _plugins_comment(skipped) -> str:
    """The lines of ``imdrive show`` naming the plug-in modules it did not import."""
    if not skipped:
        return ""
    return (
        "# plug-in modules, not imported (showing a file runs none of its code; their "
        "estimator's\n# settings are unchecked; a run needs --allow-plugins): "
        + ", ".join(skipped)
        + "\n"
    )


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


def add_parser(sub) -> None:
    """Register ``imdrive presets``, ``imdrive show`` and ``imdrive fuzzy-table``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``imdrive`` parser's sub-commands.
    """
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
        description="Print a preset's (or a scenario file's) TOML, after a first comment line "
        "saying its drive mode (vector or open-loop), or with --all every key of the scenario "
        "with its value (the defaults filled in).",
        epilog=_examples(
            "imdrive show sensorless > my.toml", "imdrive show sensorless --all | less"
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sh.add_argument("preset", metavar="PRESET_OR_FILE")
    sh.add_argument(
        "--all", action="store_true", help="every key with its value, defaults included"
    )
    sh.set_defaults(func=_cmd_show)

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
