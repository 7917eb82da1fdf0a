"""``imdrive replay``: speed estimators run open loop on a drive's recording."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from imdrive.cli._common import EXIT_OK, _examples, add_allow_plugins, output_folder


def _default_name(recording: str) -> str:
    """``out/replay-NAME``: the run folder's name, or the recording file's stem."""
    from imdrive.config.user_files import user_folder_problem

    p = Path(recording)
    return p.name if user_folder_problem(p) is None else p.stem


def _cmd_replay(args) -> int:
    from imdrive.run.recording_read import open_recording
    from imdrive.run.replay import REPLAY_FILES, replay

    # --out checked first (a default one is named after the recording, checked next), then
    # the file opened and its time checked before anything is written; every other rule is
    # checked as it streams, into a staging folder that a refusal removes
    def folder():
        return output_folder(
            args.out,
            _default_name(args.recording),
            "replay-",
            owns=lambda n: n in REPLAY_FILES,
            force=args.force,
            what="an imdrive replay",
        )

    out = folder() if args.out is not None else None
    rec = open_recording(args.recording, args.map)
    out = out if out is not None else folder()
    res = replay(
        rec,
        args.scenario,
        args.estimators,
        out,
        controller_period=args.controller_period,
        r2_law=args.r2_law,
        force=args.force,
        progress=None if not args.quiet else False,
    )
    if not args.quiet:
        s = res.summary
        parts = []
        for name, e in s["estimators"].items():
            err = e["speed_error_rpm"]
            how = e["status"] if err is None else f"{e['status']}, RMS error {err['rms']:.3g} rpm"
            if e["R2_law"] and e["R2_hat_end_ohm"] is not None:
                how += f", R2_hat {e['R2_hat_end_ohm']:.4g} ohm"
            parts.append(f"{name} ({how})")
        print(
            f"imdrive: replayed {s['rows_replayed']} rows "
            f"({s['rows_replayed'] * s['period_replayed_s']:g} s) with "
            f"{', '.join(parts)}; {s['real_time_factor']:.0f}x real time -> {out}",
            file=sys.stderr,
        )
        print(f"imdrive: R2 law: {s['R2_law']}", file=sys.stderr)
    return EXIT_OK


def add_parser(sub) -> None:
    """Register ``imdrive replay``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``imdrive`` parser's sub-commands.
    """
    r = sub.add_parser(
        "replay",
        help="run speed estimators on a drive's recording",
        description="Run registered speed estimators open loop on a recording (imdrive run "
        "--format recording writes one), through the code the closed loop runs. Writes "
        "timeseries.parquet (speed_est_<estimator>_rpm, R2_hat_<estimator>_ohm), "
        "summary.json (each estimator's speed error against the recorded encoder, its "
        "status), replay.png and report.html into out/replay-NAME unless --out says "
        "otherwise. A recording from elsewhere (CSV, Parquet or MAT) is read through a "
        "mapping file (--map, docs/replay.md); one sampled faster than the controller is "
        "decimated to its period. The file is streamed in chunks. Where the scenario runs "
        "an R2 law and the recording carries its excitation, each estimator runs the law "
        "too (R2_hat_<estimator>_ohm; --r2-law). Exit codes: "
        "imdrive --help (2: bad input, nothing written).",
        epilog=_examples(
            "imdrive run sensorless --format recording --out out/run1",
            "imdrive replay out/run1 --estimators mras,afo,ekf --out out/run1-replay",
            "imdrive replay rec.parquet --scenario my.toml --estimators smo-mras",
            "imdrive replay scope.csv --map map.toml --scenario my.toml --estimators mras,afo",
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    r.add_argument(
        "recording",
        metavar="RECORDING",
        help="recording.parquet or its run folder; a .csv, .parquet or .mat file",
    )
    r.add_argument(
        "--map",
        metavar="MAP_TOML",
        help="mapping file: each signal's column, unit and scale (docs/replay.md)",
    )
    r.add_argument(
        "--controller-period",
        choices=("scenario", "file"),
        default="scenario",
        help="run the estimators at the scenario's simulation.Ts_s (default; a faster "
        "recording is decimated to it) or at the recording's own sample period",
    )
    r.add_argument(
        "--r2-law",
        choices=("auto", "on", "off"),
        default="auto",
        help="run the scenario's R2 law on each estimator's flux error: where the scenario "
        "runs one and the recording carries its excitation (auto, default), always (on: "
        "refused where it cannot), never (off: R2_hat as the recorded controller wrote it)",
    )
    r.add_argument(
        "--scenario",
        metavar="PRESET_OR_FILE",
        help="the drive's scenario (default: the one in recording.toml beside the recording)",
    )
    r.add_argument(
        "--estimators",
        metavar="NAME[,NAME]",
        help="registered estimators to replay (default: the recorded run's)",
    )
    r.add_argument("--out", metavar="DIR", help="output folder (default out/replay-NAME)")
    r.add_argument(
        "--force", action="store_true", help="replace an --out folder holding other files"
    )
    add_allow_plugins(r)
    r.add_argument("-q", "--quiet", action="store_true")
    r.set_defaults(func=_cmd_replay)
