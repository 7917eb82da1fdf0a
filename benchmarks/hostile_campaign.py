"""A campaign of hostile inputs across imdrive's surfaces (issue 40, "must show"); not a test,
not run by the test suite.

    PYTHONPATH=src python benchmarks/hostile_campaign.py [--scale 1.0] [--seed 0]
        [--only SURFACE[,SURFACE]] [--set KEY=VALUE ...]

Each input is one call, in this process (commands through ``imdrive.cli.main``), bounded in
time; it is counted as a clean refusal (exit 2 with one line, or a one-line ConfigError), a
correct result (a documented exit: 0, 1 diverged, 3 lost control; a value returned), or a
failure (exit 4 or 5, a traceback, several error lines, a raw exception, a silent NaN, a hang,
something written where a refusal was expected, a file's secret echoed). Runs are kept short
with ``--set simulation.t_end_s=0.02`` (the default; add more with ``--set``). The surfaces:

set          ``imdrive run PRESET --set KEY=VALUE``: every scenario key x hostile values
flags        every command's flags with hostile values (read from the parser) and a hostile
             ``--out`` for the commands that write
readers      every file a command reads x hostile paths (FIFO, device, socket, folder, link to
             nothing, loop, too long, through a file, NUL byte)
writers      every command that writes x hostile ``--out``
api          23 public functions and methods x hostile arguments
machine      ``[machine] file`` naming foreign files holding a secret: never echoed
summary      corrupt ``summary.json`` / time series given to ``run`` and ``compare``
sweepfile    sweep files of hostile structure (``sweep --dry-run``)
scheduler    ``sweep --scheduler`` at local servers that speak HTTP, garbage or nothing

At the end: tried, clean refusals, correct results, failures, per surface, and each failure
(grouped by its first words) with an example input. Exit status 1 if any failure.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import random
import shutil
import socket
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from data.hostile import (  # noqa: E402
    TEXTS,
    WRITERS,
    call_api,
    commands,
    flags,
    make_path,
    path_kinds,
    positionals,
    run_cli,
)

SECRET = "hunter2-secret"
VALUES = (
    *TEXTS, "0.5", "-5", "1e6", "1e-9", "true", "false", '"text"', "[1, 2]", "{ a = 1 }", "[]",
    "{}", '"mras"', '"afo"', '"ekf"', "3.0", "0.02", "-0.0", '"' + "b" * 300 + '"',
)  # fmt: skip


class Tally:
    def __init__(self):
        self.counts = collections.defaultdict(collections.Counter)
        self.failures = collections.defaultdict(list)

    def add(self, surface: str, outcome: str, detail: str, example) -> None:
        self.counts[surface][outcome] += 1
        if outcome == "failure":
            self.failures[" ".join(str(detail).split()[:6])].append((surface, example, detail))

    def report(self) -> int:
        total = collections.Counter()
        print(f"{'surface':<11} {'tried':>6} {'refused':>8} {'correct':>8} {'failures':>8}")
        for s, c in self.counts.items():
            total.update(c)
            n = sum(c.values())
            print(f"{s:<11} {n:>6} {c['refused']:>8} {c['correct']:>8} {c['failure']:>8}")
        n = sum(total.values())
        print(f"{'all':<11} {n:>6} {total['refused']:>8} {total['correct']:>8} "
              f"{total['failure']:>8}")  # fmt: skip
        for _key, items in sorted(self.failures.items(), key=lambda kv: -len(kv[1])):
            surface, example, detail = items[0]
            print(f"\n{len(items)} x [{surface}] {detail}\n    e.g. {example!r}"[:1200])
        return total["failure"]


# -- surfaces ---------------------------------------------------------------------------------


def surface_set(rng, tmp, n, base_set, tally):
    from imdrive.config.overrides import setting_paths
    from imdrive.config.presets import preset_names

    keys = sorted(".".join(p) for p in setting_paths())
    presets = preset_names()
    for i in range(n):
        key, value = rng.choice(keys), rng.choice(VALUES)
        preset = rng.choice(presets)
        out = tmp / f"set-{i}"
        argv = ["run", preset, "-q", "--out", str(out), *base_set, "--set", f"{key}={value}"]
        outcome, detail = run_cli(argv)
        if outcome == "refused" and out.exists():
            outcome, detail = "failure", "refused but wrote its --out folder"
        tally.add("set", outcome, detail, argv[1:])
        shutil.rmtree(out, ignore_errors=True)


def _value(rng, tmp):
    if rng.random() < 0.4:
        return make_path(tmp, rng.choice(path_kinds()), rng.choice(("", ".toml", ".json", ".py")))
    return rng.choice(TEXTS)


def surface_flags(rng, tmp, n, base_set, tally):
    cmds = {k: v for k, v in commands().items() if k != "warm-up"}
    refused_out = [k for k in path_kinds() if k != "folder"]
    for i in range(n):
        name = rng.choice(sorted(cmds))
        parser = cmds[name]
        work = tmp / f"flags-{i}"
        argv = [name]
        for action in positionals(parser):
            if action.nargs == "?" and rng.random() < 0.5:
                continue
            argv += [_value(rng, work) for _ in range(2 if action.nargs == "+" else 1)]
        for flag, takes_value in flags(parser):
            if name in WRITERS and flag in ("--out", "--force", "--resume", "--list", "--show"):
                continue
            if rng.random() < 0.5:
                argv += [flag, _value(rng, work)] if takes_value else [flag]
        if name in WRITERS:
            argv += ["--out", make_path(work, rng.choice(refused_out))]
        outcome, detail = run_cli(argv, bound_s=90.0)
        if name in WRITERS and outcome == "correct":
            outcome, detail = "failure", f"a hostile --out was accepted ({detail})"
        tally.add("flags", outcome, detail, argv)
        shutil.rmtree(work, ignore_errors=True)


def _readers(tmp):
    rec = tmp / "rec.csv"
    rec.write_text("time_s\n0\n")
    sweep = tmp / "base.toml"

    def with_base(p):
        sweep.write_text(f'name = "b"\nbase = {json.dumps(p)}\n[axes]\nR2_ratio = [1.0]\n')
        return ["sweep", str(sweep), "--dry-run"]

    def result_with(p):
        run = tmp / "result"
        run.mkdir(exist_ok=True)
        link = run / "summary.json"
        link.unlink(missing_ok=True)
        try:
            link.symlink_to(p)
        except (OSError, ValueError):
            return ["compare", p]
        return ["compare", str(run)]

    return {
        "run": (".toml", lambda p: ["run", p, "-q", "--out", str(tmp / "o")]),
        "run summary": (".json", lambda p: ["run", p, "-q", "--out", str(tmp / "o")]),
        "machine.file": (".toml", lambda p: ["run", "sensorless", "-q", "--out", str(tmp / "o"),
                                             "--set", f"machine.file={json.dumps(p)}"]),
        "plugin": (".py", lambda p: ["run", "sensorless", "-q", "--allow-plugins", "--out",
                                     str(tmp / "o"), "--set",
                                     f"plugins.modules=[{json.dumps(p)}]"]),
        "show": (".toml", lambda p: ["show", p]),
        "show --all": (".toml", lambda p: ["show", p, "--all"]),
        "sweep": (".toml", lambda p: ["sweep", p, "--dry-run"]),
        "sweep base": (".toml", with_base),
        "stability": (".toml", lambda p: ["stability", p, "--out", str(tmp / "o")]),
        "bench --base": (".toml", lambda p: ["bench-estimators", "--base", p, "--out",
                                             str(tmp / "o")]),
        "commission": (".toml", lambda p: ["commission", p, "--out", str(tmp / "o")]),
        "compare": ("", lambda p: ["compare", p]),
        "compare summary": (".json", result_with),
        "replay": (".parquet", lambda p: ["replay", p, "--out", str(tmp / "o")]),
        "replay --map": (".toml", lambda p: ["replay", str(rec), "--map", p, "--out",
                                             str(tmp / "o")]),
    }  # fmt: skip


def surface_readers(rng, tmp, n, base_set, tally):
    kinds = [k for k in path_kinds() if k not in ("empty", ".", "..", "file")] + ["nul"]
    for i in range(n):
        work = tmp / f"readers-{i}"
        work.mkdir(parents=True)
        readers = _readers(work)
        name = rng.choice(sorted(readers))
        suffix, argv_of = readers[name]
        kind = rng.choice(kinds)
        if kind == "folder" and name == "compare":
            kind = "fifo"
        p = str(work / f"a\0b{suffix}") if kind == "nul" else make_path(work, kind, suffix)
        argv = argv_of(p)
        outcome, detail = run_cli(argv)
        if outcome == "correct":
            outcome, detail = "failure", f"read a {kind} as a file ({detail})"
        if (work / "o").exists():
            outcome, detail = "failure", "wrote its --out after a refused input"
        tally.add("readers", outcome, detail, (name, kind))
        shutil.rmtree(work, ignore_errors=True)


NAMEPLATE = ["--power-kw=2.2", "--voltage=400", "--frequency=50", "--poles=4", "--speed=1436",
             "--current=5", "--pf=0.79", "--efficiency=0.82"]  # fmt: skip


def surface_writers(rng, tmp, n, base_set, tally):
    rec = tmp / "rec.csv"
    tmp.mkdir(parents=True, exist_ok=True)
    rec.write_text("time_s\n0\n")
    writers = {
        "run": lambda o: ["run", "sensorless", "-q", "--out", o],
        "sweep": lambda o: ["sweep", "detuning-map", "-q", "--out", o],
        "stability": lambda o: ["stability", "sensorless", "--out", o],
        "bench-estimators": lambda o: ["bench-estimators", "--out", o],
        "compare": lambda o: ["compare", str(tmp / "none"), "--out", o],
        "paper": lambda o: ["paper", "--out", o],
        "replay": lambda o: ["replay", str(rec), "--out", o],
        "commission": lambda o: ["commission", "sensorless", "--out", o],
        "machine-from-nameplate": lambda o: ["machine-from-nameplate", *NAMEPLATE, "--out", o],
    }
    kinds = [k for k in path_kinds() if k != "folder"] + ["nul", "link-to-foreign"]
    for i in range(n):
        work = tmp / f"writers-{i}"
        name, kind = rng.choice(sorted(writers)), rng.choice(kinds)
        if kind == "nul":
            out = str(work / "a\0b")
            work.mkdir(parents=True)
        elif kind == "link-to-foreign":
            target = make_path(work, "foreign-folder")
            (work / "link").symlink_to(target)
            out = str(work / "link")
        elif name == "machine-from-nameplate" and kind == "foreign-folder":
            out = make_path(work, "folder")
        else:
            out = make_path(work, kind)
        before = sorted(str(p) for p in work.rglob("*"))
        outcome, detail = run_cli(writers[name](out))
        if name == "machine-from-nameplate" and kind == "file" and outcome == "correct":
            pass  # --out FILE names a file to write: a regular one is replaced, as asked
        elif outcome == "correct":
            outcome, detail = "failure", f"wrote at a {kind} ({detail})"
        elif outcome != "correct" and sorted(str(p) for p in work.rglob("*")) != before:
            outcome, detail = "failure", "refused but changed the folder"
        tally.add("writers", outcome, detail, (name, kind))
        shutil.rmtree(work, ignore_errors=True)


def surface_api(rng, tmp, n, base_set, tally):
    import math

    from imdrive import Scenario, simulate

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "package"))
    from test_api_properties import POOL, _functions

    res = simulate(Scenario.read("sensorless", ["simulation.t_end_s=0.02"]))
    funcs = _functions(res)
    kinds = ("fifo", "socket", "device", "dangling", "too-long", "folder", "under-a-file",
             "loop", "file")  # fmt: skip
    for i in range(n):
        name = rng.choice(sorted(funcs))
        fn, k = funcs[name]
        work = tmp / f"api-{i}"
        args = [
            make_path(work, rng.choice(kinds), rng.choice(("", ".toml", ".json", ".csv")))
            if rng.random() < 0.25
            else rng.choice(POOL)
            for _ in range(k)
        ]
        outcome, detail = call_api(fn, *args)
        tally.add(
            "api",
            outcome,
            detail,
            (name, [a if not isinstance(a, float) or math.isfinite(a) else str(a) for a in args]),
        )
        shutil.rmtree(work, ignore_errors=True)


def surface_machine(rng, tmp, n, base_set, tally):
    shapes = (
        lambda: f'R1_ohm = "{SECRET}"\n',
        lambda: f'password = "{SECRET}"\nuser = "bob"\n',
        lambda: f'preset = "{SECRET}"\n',
        lambda: f'[machine]\n{rng.choice(["R1_ohm", "pole_pairs", "J_kgm2"])} = "{SECRET}"\n',
        lambda: f'{rng.choice(["R1_ohm", "M_H"])} = {{ v = "{SECRET}" }}\n',
        lambda: f'[server]\ntoken = "{SECRET}"\nport = 8080\n',
        lambda: f'aws_secret = "{SECRET}"\nR1_ohm = 0.4\n',
        lambda: f'R1_ohm = ["{SECRET}"]\n',
        lambda: f"{SECRET.replace('-', '_')} = 1\n",
        lambda: f'description = "{SECRET}"\nR2_ohm = -1\n',
    )
    for i in range(n):
        f = tmp / f"foreign-{i}.toml"
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(rng.choice(shapes)())
        argv = ["run", "sensorless", "-q", "--out", str(tmp / f"m-{i}"), *base_set,
                "--set", f"machine.file={json.dumps(str(f))}"]  # fmt: skip
        from imdrive.cli import main  # noqa: F401  (run_cli's import, warmed)

        outcome, detail = run_cli(argv)
        if "hunter2" in detail:
            outcome, detail = "failure", "a foreign file's value echoed"
        tally.add("machine", outcome, detail, f.read_text())
        shutil.rmtree(tmp / f"m-{i}", ignore_errors=True)


def _good_result(tmp: Path, base_set) -> Path:
    out = tmp / "good"
    if not out.exists():
        run_cli(["run", "sensorless", "-q", "--out", str(out), "--format", "csv", *base_set])
    return out


def surface_summary(rng, tmp, n, base_set, tally):
    good = _good_result(tmp, base_set)
    text = (good / "summary.json").read_text()
    csv = (good / "timeseries.csv").read_text()
    corruptions = (
        lambda: text[: rng.randrange(len(text))],
        lambda: "[" * rng.choice((10, 1000, 100000)),
        lambda: text.encode("utf-16"),
        lambda: bytes(rng.randrange(256) for _ in range(rng.randrange(1, 200))),
        lambda: json.dumps([1, 2, 3]),
        lambda: json.dumps({"scenario": rng.choice(VALUES)}),
        lambda: text.replace('"sensorless"', json.dumps(rng.choice(VALUES)), 1),
        lambda: text.replace("0.", rng.choice(("1e999", "-", "nan", "x")), 1),
        lambda: "",
    )
    csv_corruptions = (
        lambda: "", lambda: csv.splitlines()[0] + "\n", lambda: "a,b\nx,y\n",
        lambda: csv.replace("time_s", "t", 1), lambda: csv[: rng.randrange(len(csv))],
        lambda: csv.replace(",", ";"), lambda: "\0" * 100,
    )  # fmt: skip
    for i in range(n):
        run = tmp / f"summary-{i}"
        shutil.copytree(good, run)
        if rng.random() < 0.6:
            data = rng.choice(corruptions)()
            target = run / "summary.json"
        else:
            data = rng.choice(csv_corruptions)()
            target = run / "timeseries.csv"
        if isinstance(data, str):
            target.write_text(data, encoding="utf-8", errors="surrogateescape")
        else:
            target.write_bytes(data)
        if rng.random() < 0.5:
            argv = ["compare", str(run), str(good), "--out", str(tmp / f"cmp-{i}")]
        else:
            argv = ["run", str(run / "summary.json"), "-q", "--out", str(tmp / f"re-{i}"),
                    *base_set]  # fmt: skip
        outcome, detail = run_cli(argv)
        tally.add("summary", outcome, detail, (argv[0], target.name))
        for p in (run, tmp / f"cmp-{i}", tmp / f"re-{i}"):
            shutil.rmtree(p, ignore_errors=True)


def surface_sweepfile(rng, tmp, n, base_set, tally):
    axes = ("R2_ratio", "load_Nm", "speed_rpm", "estimator.R2_ohm", "compensator.enabled",
            "control.speed_ref_rpm", "plugins.modules", "nosuch", "machine.file",
            "injection.frequency_Hz", "injection.frequency_pu", "simulation.t_end_s")  # fmt: skip
    values = ("[0.8, 1.2]", "[]", "[1]", "{ min = 0, max = 1, num = 3 }", "{ min = 1, max = 0 }",
              "{ num = 1e9 }", "[[1], [2]]", '["a", "b"]', "[nan, 1]", "[1e308]", "[true]",
              "{ list = [1] }", "[{ initial = 0 }]", "3", '"x"')  # fmt: skip
    tops = ('name = "x"\n', 'name = "../../x"\n', "name = 5\n", "", 'description = "d"\n',
            "chunk_size = 0\n", "chunk_size = 1e9\n", "window_s = -1\n", "samples = 5\n",
            'base = "nosuch"\n', "random = true\nsamples = 3\n")  # fmt: skip
    for i in range(n):
        text = 'base = "sensorless"\n' + rng.choice(tops) + "[axes]\n"
        for _ in range(rng.randrange(0, 4)):
            text += f'"{rng.choice(axes)}" = {rng.choice(values)}\n'
        if rng.random() < 0.3:
            text += '[axes.variant]\na = {}\nb = { "estimator.R2_ohm" = 0.9 }\n'
        f = tmp / f"sweep-{i}.toml"
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text)
        argv = ["sweep", str(f), "--dry-run", "--max-runs", "100"]
        outcome, detail = run_cli(argv)
        tally.add("sweepfile", outcome, detail, text)


def _server(reply):
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(16)
    done = threading.Event()

    def serve():
        s.settimeout(0.2)
        while not done.is_set():
            try:
                c, _ = s.accept()
            except OSError:
                continue
            threading.Thread(target=lambda c=c: _answer(c, reply, done), daemon=True).start()

    threading.Thread(target=serve, daemon=True).start()
    return f"tcp://127.0.0.1:{s.getsockname()[1]}", lambda: (done.set(), s.close())


def _answer(c, reply, done):
    try:
        reply(c)
        done.wait(20)
    except OSError:
        pass
    finally:
        c.close()


def surface_scheduler(rng, tmp, n, base_set, tally):
    try:
        import distributed  # noqa: F401
    except ImportError:
        return
    replies = {
        "http": lambda c: (c.settimeout(5), c.recv(4096),
                           c.sendall(b"HTTP/1.1 400 Bad Request\r\n\r\n")),
        "http-first": lambda c: c.sendall(b"HTTP/1.1 200 OK\r\n\r\n"),
        "garbage": lambda c: c.sendall(bytes(rng.randrange(256) for _ in range(64))),
        "huge": lambda c: c.sendall(b"\xff" * 64),
        "silent": lambda c: None,
        "close": lambda c: c.close(),
    }  # fmt: skip
    sweep = tmp / "tiny.toml"
    tmp.mkdir(parents=True, exist_ok=True)
    sweep.write_text('name = "t"\nbase = "sensorless"\n[set]\nsimulation.t_end_s = 0.004\n'
                     "[axes]\nR2_ratio = [1.0]\n")  # fmt: skip
    for i in range(n):
        kind = rng.choice(sorted(replies))
        address, stop = _server(replies[kind])
        argv = ["sweep", str(sweep), "--out", str(tmp / f"s-{i}"), "-q", "--scheduler", address,
                "--connect-timeout", "1"]  # fmt: skip
        t0 = time.perf_counter()
        outcome, detail = run_cli(argv, bound_s=30.0)
        if outcome == "correct":
            outcome, detail = "failure", f"a {kind} server was taken for a scheduler"
        elif time.perf_counter() - t0 > 15:
            outcome, detail = "failure", f"took {time.perf_counter() - t0:.0f} s"
        tally.add("scheduler", outcome, detail, kind)
        stop()


SURFACES = {
    "set": (surface_set, 1500),
    "flags": (surface_flags, 1300),
    "readers": (surface_readers, 500),
    "writers": (surface_writers, 400),
    "api": (surface_api, 1000),
    "machine": (surface_machine, 200),
    "summary": (surface_summary, 250),
    "sweepfile": (surface_sweepfile, 250),
    "scheduler": (surface_scheduler, 30),
}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scale", type=float, default=1.0, help="multiply every surface's count")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--only", help="comma-separated surfaces")
    p.add_argument("--set", action="append", default=[], help="KEY=VALUE for every run")
    args = p.parse_args(argv)
    base_set = []
    for kv in ["simulation.t_end_s=0.02", *args.set]:
        base_set += ["--set", kv]
    only = set(args.only.split(",")) if args.only else set(SURFACES)
    rng = random.Random(args.seed)
    tally = Tally()
    t0 = time.perf_counter()
    here = os.getcwd()
    with tempfile.TemporaryDirectory(prefix="imdrive-campaign-") as root:
        os.chdir(root)  # what an accepted relative path writes (res.save("x")) lands here
        for name, (fn, count) in SURFACES.items():
            if name not in only:
                continue
            t = time.perf_counter()
            fn(rng, Path(root) / name, max(1, round(count * args.scale)), base_set, tally)
            print(f"# {name}: {sum(tally.counts[name].values())} inputs in "
                  f"{time.perf_counter() - t:.0f} s", file=sys.stderr, flush=True)  # fmt: skip
        os.chdir(here)
    print(f"# {time.perf_counter() - t0:.0f} s in all", file=sys.stderr)
    return 1 if tally.report() else 0


if __name__ == "__main__":
    sys.exit(main())
