"""``imdrive stability``: small-signal stability maps over speed x load torque."""

from __future__ import annotations

import argparse
import sys
import time

from imdrive.cli._common import EXIT_OK, _examples, add_allow_plugins, add_force, output_folder
from imdrive.errors import ConfigError


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


def _default_grid(scenario) -> tuple[str, str]:
    """The map's default axes in per-unit of the machine: speeds 0 to the rated speed (50
    points), load torques within twice the rated torque (41 points), as ``MIN:MAX:N``."""
    from imdrive.config.machine import rated_point

    rp = rated_point(scenario.machine)
    n, t = rp.speed_rpm, 2.0 * rp.torque_Nm
    return f"0:{n:.6g}:50", f"{-t:.6g}:{t:.6g}:41"


#: how far from the machine's rated point a map may reach (multiples of the synchronous
#: speed and of the rated torque): beyond, the linearisation's matrices overflow
MAP_REACH = 10.0


def _check_within_machine(scenario, speeds, torques) -> None:
    """The map's axes within :data:`MAP_REACH` times the machine's synchronous speed and
    rated torque (a one-line ConfigError naming the option otherwise)."""
    from imdrive.config.machine import rated_point

    rp = rated_point(scenario.machine)
    for name, values, bound, unit, what in (
        ("--speeds", speeds, MAP_REACH * rp.synchronous_speed_rpm, "rpm", "synchronous speed"),
        ("--torques", torques, MAP_REACH * rp.torque_Nm, "N m", "rated torque"),
    ):
        worst = float(max(abs(values[0]), abs(values[-1])))
        if worst > bound:
            raise ConfigError(
                name,
                f"{worst:.4g} {unit} is beyond {MAP_REACH:g} x the machine's {what} "
                f"({bound:.4g} {unit})",
            )


def _owns_stability_file(name: str) -> bool:
    """The files ``imdrive stability`` writes: stability.csv, stability*.png."""
    return name == "stability.csv" or (name.startswith("stability") and name.endswith(".png"))


def _cmd_stability(args) -> int:
    import pandas as pd

    from imdrive._io import replace_folder
    from imdrive.config.scenario import Scenario

    r1 = _parse_ratios(args.R1_ratios, "--r1-ratios")
    r2 = _parse_ratios(args.R2_ratios, "--r2-ratios")
    scenario = Scenario.read(args.scenario, args.set or [])
    speed_range, torque_range = _default_grid(scenario)
    speeds = _parse_range(args.speeds or speed_range, "--speeds")
    torques = _parse_range(args.torques or torque_range, "--torques")
    _check_within_machine(scenario, speeds, torques)
    out = output_folder(
        args.out, owns=_owns_stability_file, force=args.force, what="a stability map"
    )

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
    # the folder as a whole, as imdrive run writes its own: staged, then put in place, so a
    # failure (or a kill) in a figure leaves no complete-looking stability.csv behind
    with replace_folder(out) as staging:
        pd.concat(frames, ignore_index=True).to_csv(staging / "stability.csv", index=False)
        plot_map(base, staging / "stability.png", title=f"{scenario.name}: small-signal stability")
        for name, over in (("stability_R1.png", over_r1), ("stability_R2.png", over_r2)):
            if over:
                plot_overlay({"as configured": base, **over}, staging / name)
    if base.attrs.get("note"):  # with -q too: it says what part of the map means
        print(f"imdrive: {base.attrs['note']}", file=sys.stderr)
    if not args.quiet:
        ok = base["status"] == "ok"
        print(
            f"imdrive: stability of {scenario.name}: {len(base)} points in {wall:.2f} s, "
            f"{int(base['stable'].sum())} stable, {int(ok.sum() - base['stable'].sum())} unstable, "
            f"{int((~ok).sum())} without steady state -> {out / 'stability.csv'}",
            file=sys.stderr,
        )
    return EXIT_OK


def add_parser(sub) -> None:
    """Register ``imdrive stability``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``imdrive`` parser's sub-commands.
    """
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
    st.add_argument(
        "--speeds",
        metavar="MIN:MAX:N",
        help="speed refs, rpm (default 0 to the machine's rated speed, 50 points)",
    )
    st.add_argument(
        "--torques",
        metavar="MIN:MAX:N",
        help="load torques, N m (default within twice the machine's rated torque, 41 points; "
        "write --torques=-24:24:40 for a negative start)",
    )
    st.add_argument(
        "--r1-ratios", dest="R1_ratios", metavar="A,B,...", help="overlay maps for R1_hat/R1"
    )
    st.add_argument(
        "--r2-ratios", dest="R2_ratios", metavar="A,B,...", help="overlay maps for R2_hat/R2"
    )
    st.add_argument("--out", metavar="DIR", required=True)
    add_force(st, "a stability map")
    st.add_argument("-q", "--quiet", action="store_true")
    add_allow_plugins(st)
    st.set_defaults(func=_cmd_stability)
