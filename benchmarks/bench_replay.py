"""Replay of a 10^7-row recording: wall time, real-time factor and peak memory.

The targets (issue 41): a 10^7-row recording replayed in under 1 GiB, at least 100 x real
time for three estimators.

The file: the ``sensorless`` preset (``--preset``; ``injection-robust``: each estimator runs
the R2 law too) is simulated and recorded for 11 s under a speed cycle
(0 -> +900 rpm -> -900 rpm -> 0); the 10 s from t = 1 s (magnetised, at rest) to 11 s (at
rest again) are written again and again, time continued, until the file has ``--rows`` rows
(10^7 at Ts = 100 us: 1000 s of drive). The tiles join where the drive is at rest and
magnetised, so the estimators see a nearly continuous recording; the join is not exact (the
load and the flux are not bit for bit the same), which matters nothing for time and memory.
The file is written a row group at a time (``pyarrow.parquet.ParquetWriter``), all columns of
``recording.parquet``, encoded as imdrive writes it
(:func:`imdrive.run.recording.parquet_options`).

The measurement: ``imdrive replay FILE --scenario sensorless --estimators ... --out DIR -q``
in a child process (after one warm-up run that compiles or loads the estimators from the
numba cache), ``--repeat`` times; wall time of the command, the replay's own elapsed time
and real-time factor (``summary.json``), each estimator's CPU time (its kernel's thread
time), the child's CPU time (user + system, all its threads: the work an idle machine would
spread over its cores) and its peak resident memory
(``resource.getrusage(RUSAGE_CHILDREN)``, each run in a fresh child so the figures are its
own).

Usage::

    python benchmarks/bench_replay.py [--rows 10000000] [--estimators mras,afo,ekf]
        [--repeat 3] [--preset sensorless] [--csv] [--keep DIR] [--stages]

``--stages`` also runs the replay's stages one after the other in this process and prints
each one's CPU time (:func:`stages`): where the time goes, whatever the machine's load.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _measured import machine_line, span

CYCLE = {
    "initial": 0,
    "changes": [
        {"at": 1.5, "to": 900, "over": 1.0},
        {"at": 4.0, "to": -900, "over": 2.0},
        {"at": 7.5, "to": 0, "over": 1.0},
    ],
}


def make_file(path: Path, rows: int, csv: bool, preset: str = "sensorless") -> float:
    """Write the recording (module docstring); return the seconds it took."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    import imdrive as im
    from imdrive.run.recording import parquet_options
    from imdrive.run.simulate import simulate

    t0 = time.perf_counter()
    sc = im.Scenario.read(preset).with_overrides(
        {"simulation.t_end_s": 11.0, "control.speed_ref_rpm": CYCLE}
    )
    res = simulate(sc, record=True)
    Ts = sc.simulation.Ts_s
    k0 = int(round(1.0 / Ts))
    k1 = int(round(11.0 / Ts))
    tile = {k: v[k0:k1] for k, v in res.recording.items()}
    n_tile = k1 - k0
    writer = None
    done = 0
    while done < rows:
        n = min(n_tile, rows - done)
        cols = {k: v[:n] for k, v in tile.items()}
        cols["time_s"] = (done + np.arange(n)) * Ts
        table = pa.table(cols)
        if csv:
            if writer is None:
                writer = pcsv.CSVWriter(str(path), table.schema)
            writer.write_table(table)
        else:
            if writer is None:
                opts = parquet_options(table.schema)  # as imdrive writes recording.parquet
                writer = pq.ParquetWriter(str(path), table.schema, **opts)
            writer.write_table(table, row_group_size=1 << 18)
        done += n
    writer.close()
    return time.perf_counter() - t0


def replay_once(path: Path, estimators: str, out: Path, preset: str = "sensorless") -> dict:
    """One replay in a fresh child process: its wall time and peak RSS."""
    code = (
        "import resource, subprocess, sys, time; t0 = time.perf_counter(); "
        "rc = subprocess.call(sys.argv[1:]); "
        "print(time.perf_counter() - t0, "
        "resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, rc, "
        "resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime "
        "+ resource.getrusage(resource.RUSAGE_CHILDREN).ru_stime)"
    )
    cmd = [sys.executable, "-m", "imdrive", "replay", str(path), "--scenario", preset]
    cmd += ["--estimators", estimators, "--out", str(out), "--force", "-q"]
    line = subprocess.run(
        [sys.executable, "-c", code, *cmd], capture_output=True, text=True, check=True
    ).stdout.split()
    wall, rss_kb, rc, cpu = float(line[0]), int(line[1]), int(line[2]), float(line[3])
    if rc != 0:
        raise SystemExit(f"imdrive replay failed (exit {rc})")
    summary = json.loads((out / "summary.json").read_text())
    return {
        "wall_s": wall,
        "process_cpu_s": cpu,
        "peak_rss_MiB": rss_kb / 1024.0,
        "elapsed_s": summary["elapsed_s"],
        "real_time_factor": summary["real_time_factor"],
        "estimators_s": summary["wall_time_s"],
        **{f"cpu_{name}_s": cpu for name, cpu in summary.get("estimators_cpu_s", {}).items()},
        "rows": summary["rows_replayed"],
    }


def stages(path: Path, estimators: str, chunk_rows: int, preset: str = "sensorless") -> dict:
    """The replay's stages one after the other in this process, one thread, each stage's CPU
    time (``time.process_time``): the pass over the time column, reading and checking the
    chunks, the unit check, building the rows, each estimator, writing the estimates. What
    the threads of a replay spread over the cores, stage by stage (it uses the replay's
    internals, ``imdrive.run.replay``)."""
    import numpy as np

    from imdrive.run import replay as rp
    from imdrive.run.build import build_arrays
    from imdrive.run.recording_read import open_recording
    from imdrive.run.replay_inputs import _limits, _scenario, _scenario_of, check_units
    from imdrive.run.replay_stream import EstimateWriter

    clock = time.process_time
    c = clock()
    rec = open_recording(path)
    cpu = {"time_pass": clock() - c, "read_check": 0.0, "units": 0.0, "rows": 0.0}
    sc = _scenario(rec, preset)
    limits = _limits(sc)
    names = estimators.split(",")
    drives = {n: build_arrays(_scenario_of(sc, n)) for n in names}
    Ts = float(drives[names[0]].params.sim[0]["Ts"])
    law, _ = rp.law_replayed("auto", sc, drives[names[0]].params.comp, rec.columns)
    # compiled before timing
    ests = [rp._Estimator(n, drives[n], Ts, True, law, rec.rows) for n in names]
    prev = rp._prev_row(drives[names[0]].state0.sample[0])
    rp.replay_rows({k: np.zeros(0) for k in rp.REQUIRED}, prev.copy())
    cpu.update({n: 0.0 for n in names}, write=0.0)
    rows = None
    with tempfile.TemporaryDirectory() as tmp:
        writer = EstimateWriter(Path(tmp), background=False)
        chunks = iter(rec.chunks(chunk_rows))
        while True:
            c = clock()
            try:
                k0, cols = next(chunks)
            except StopIteration:
                break
            cpu["read_check"] += clock() - c
            c = clock()
            check_units(rec, cols, k0, limits)
            cpu["units"] += clock() - c
            c = clock()
            rows, _, _ = rp.replay_rows(cols, prev, rows)
            cpu["rows"] += clock() - c
            sig = {"time_s": cols["time_s"], "speed_enc_rpm": cols["speed_enc_rpm"]}
            for e in ests:
                c = clock()
                sig[f"speed_{e.name}"], sig[f"R2_{e.name}"] = e.run(rows, cols["speed_enc_rpm"])
                cpu[e.name] += clock() - c
            c = clock()
            writer.write(sig)
            cpu["write"] += clock() - c
        c = clock()
        writer.close()
        cpu["write"] += clock() - c
    return cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=10_000_000)
    ap.add_argument("--estimators", default="mras,afo,ekf")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument(
        "--preset",
        default="sensorless",
        help="the drive recorded and replayed (injection-robust: each estimator runs the R2 law)",
    )
    ap.add_argument("--csv", action="store_true", help="a CSV file instead of Parquet")
    ap.add_argument("--keep", metavar="DIR", help="write the file there and keep it")
    ap.add_argument(
        "--stages", action="store_true", help="also each stage's CPU time, in one thread"
    )
    args = ap.parse_args()
    print(machine_line())
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.keep or tmp)
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / ("recording.csv" if args.csv else "big.parquet")
        if not path.exists():
            took = make_file(path, args.rows, args.csv, args.preset)
            print(f"wrote {path} ({os.path.getsize(path) / 2**20:.0f} MiB) in {took:.0f} s")
        out = Path(tmp) / "replay"
        replay_once(path, args.estimators, out, args.preset)  # warm-up: the numba cache
        runs = [replay_once(path, args.estimators, out, args.preset) for _ in range(args.repeat)]
        if args.stages:
            from imdrive.run.recording_read import CHUNK_ROWS

            parts = [
                stages(path, args.estimators, CHUNK_ROWS, args.preset) for _ in range(args.repeat)
            ]
    r = runs[0]
    print(f"{r['rows']} rows ({r['rows'] * 1e-4:g} s of drive), estimators {args.estimators}:")
    cpu = [(k, "s") for k in r if k.startswith("cpu_")]
    for key, unit in (
        ("wall_s", "s"),
        ("process_cpu_s", "s"),
        ("elapsed_s", "s"),
        ("estimators_s", "s"),
        *cpu,
        ("real_time_factor", "x"),
        ("peak_rss_MiB", "MiB"),
    ):
        print(f"  {key:18s} {span([x[key] for x in runs], unit)}")
    if args.stages:
        print("  CPU time by stage, one thread:")
        for key in parts[0]:
            print(f"    {key:16s} {span([x[key] for x in parts], 's')}")


if __name__ == "__main__":
    main()
