"""``imdrive bench-estimators``: the estimator test protocol, on its own drives or on yours."""

from __future__ import annotations

import argparse
import sys
import time

from imdrive.cli._common import EXIT_OK, _examples, add_allow_plugins, add_force, output_folder
from imdrive.errors import ConfigError


def _owns_bench_file(name: str) -> bool:
    """The files ``imdrive bench-estimators`` writes: estimators.csv, estimators.md, PNGs."""
    return name in ("estimators.csv", "estimators.md") or name.endswith(".png")


def _numbers(text: str, option: str) -> list[float]:
    """``"50,150,-30"`` -> ``[50.0, 150.0, -30.0]`` (a ConfigError naming the option)."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ConfigError(option, f"a comma-separated list of numbers, not {text!r}") from None
    if not values:
        raise ConfigError(option, "is empty")
    bad = [v for v in values if not abs(v) < float("inf")]
    if bad:
        raise ConfigError(option, f"must be finite numbers, got {bad[0]!r}")
    return values


def _rated_torque(base: str, overrides: list[str]) -> float:
    """The rated torque of the base scenario's machine, N m (the default load)."""
    from imdrive.config.machine import rated_point
    from imdrive.config.scenario import Scenario

    machine = Scenario.read(base, overrides).machine
    try:
        return float(rated_point(machine).torque_Nm)
    except ConfigError:
        raise ConfigError(
            "--loads", f"{base}: its machine has no rated point; give the loads (N m)"
        ) from None


def bench_setup(args) -> dict:
    """The keyword arguments of :func:`imdrive.bench.report.bench_estimators` for ``args``."""
    from imdrive.bench.protocol import DRIVES, QUICK_CASES, protocol_cases, steady_cases
    from imdrive.cli.run import _run_folder_name

    overrides = list(args.set or [])
    kw: dict = {"quick": args.quick, "overrides": overrides}
    if args.estimators is not None:
        from imdrive.bench.protocol import ESTIMATORS

        names = [e.strip() for e in args.estimators.split(",") if e.strip()]
        if not names:
            raise ConfigError(
                "--estimators", f"is empty: name one or more of {', '.join(ESTIMATORS)}"
            )
        unknown = [e for e in names if e not in ESTIMATORS]
        if unknown:
            raise ConfigError(
                "--estimators", f"no configuration {unknown[0]!r}; known: {', '.join(ESTIMATORS)}"
            )
        kw["estimators"] = names
    base = args.base
    if base is not None:
        from imdrive.config.scenario import Scenario

        mode = Scenario.read(base, overrides).drive.mode
        if mode != "vector":  # the bench holds a speed reference with an estimator in the loop
            raise ConfigError(
                "--base",
                f'{base!r} runs open-loop ([drive] mode = "{mode}"): the estimator bench needs '
                'a field-oriented drive (add --set drive.mode="vector" or choose another)',
            )
        kw["drives"] = {_run_folder_name(base): base}
    if args.speeds is not None or args.loads is not None:
        ref = base or DRIVES["average"]
        speeds = _numbers(args.speeds, "--speeds") if args.speeds else [1000.0, 150.0, 30.0]
        loads = _numbers(args.loads, "--loads") if args.loads else [_rated_torque(ref, overrides)]
        kw["cases"] = steady_cases(speeds, loads)
    elif base is not None:  # the protocol's cases at the base machine's rated load
        cases = protocol_cases(_rated_torque(base, overrides))
        if args.quick:
            cases = {k: cases[k] for k in QUICK_CASES}
        kw["cases"] = cases
    return kw


def _cmd_bench_estimators(args) -> int:
    from imdrive.bench.report import bench_estimators

    out = output_folder(
        args.out, owns=_owns_bench_file, force=args.force, what="an estimator benchmark"
    )
    t0 = time.perf_counter()
    s = bench_estimators(out, **bench_setup(args))
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
    from imdrive.bench.protocol import ESTIMATORS

    be = sub.add_parser(
        "bench-estimators",
        help="run the estimator test protocol: CSV, a figure per metric, a Markdown table",
        description="Every speed estimator and R2 adaptation method on the same scenarios "
        "and metrics (docs/estimators.md): estimators.csv, <metric>.png and estimators.md in "
        "DIR. By default the protocol's drives (presets sensorless and sensorless-realistic) "
        "and cases; --base runs it on your scenario (a preset or a file; its machine's rated "
        "torque is the rated load, its parameter errors are relative to its machine), --set "
        "changes it, --speeds/--loads replace the cases by steady states on that grid.",
        epilog=_examples(
            "imdrive bench-estimators --quick --out out/bench",
            "imdrive bench-estimators --base my-drive.toml --estimators mras,afo,ekf "
            "--speeds 50 --loads 0,10 --out out/bench-50rpm",
            "imdrive bench-estimators --base sensorless-realistic "
            '--set machine.preset=\\"aalto-2.2kw\\" --set inverter.Vdc_V=560 --out out/b',
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    be.add_argument("--quick", action="store_true", help="a small subset (CI)")
    be.add_argument("--out", metavar="DIR", required=True)
    add_force(be, "an estimator benchmark")
    be.add_argument(
        "--base",
        metavar="PRESET_OR_FILE",
        help="the drive to bench on, in place of the protocol's two",
    )
    be.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="override a value of the drive(s), as imdrive run --set (repeatable)",
    )
    be.add_argument(
        "--speeds",
        metavar="RPM,...",
        help="steady-state cases at these speeds (default 1000,150,30 when --loads is given)",
    )
    be.add_argument(
        "--loads",
        metavar="NM,...",
        help="load torques of the steady-state cases, N m (default: the machine's rated torque)",
    )
    be.add_argument(
        "--estimators",
        metavar="NAME,...",
        help="the configurations to compare (default: all): " + ", ".join(ESTIMATORS),
    )
    be.add_argument("-q", "--quiet", action="store_true")
    add_allow_plugins(be)
    be.set_defaults(func=_cmd_bench_estimators)
