"""Paths the user gives (issue 40, class 13, and the special-file test over every command that
reads): a name too long, a path through a file, a link to nothing, a FIFO, a device, a folder
where a file is read and a NUL byte are the user's input to fix, exit 2 with one line, for
every file or folder any command reads; never exit 4 ("File name too long") and never a hang
(a FIFO opened for reading blocks until a writer comes). None of these simulates a drive."""

from __future__ import annotations

import io
import os
import socket
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from imdrive.cli import build_parser, main

LONG = "a" * 300


def _main(*argv) -> tuple[int, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        rc = main(list(argv))
    return rc, err.getvalue()


def _hostile(tmp: Path, kind: str, suffix: str) -> str:
    """A path of ``kind`` in ``tmp`` whose name ends with ``suffix``."""
    if kind == "too-long":
        return str(tmp / (LONG + suffix))
    if kind == "long-part-deep":
        return str(tmp / LONG / ("x" + suffix))
    if kind == "through-a-file":
        (tmp / "file").write_text("x")
        return str(tmp / "file" / ("x" + suffix))
    if kind == "dangling-link":
        p = tmp / ("dangling" + suffix)
        p.symlink_to(tmp / "nothing-here")
        return str(p)
    if kind == "fifo":
        p = tmp / ("fifo" + suffix)
        os.mkfifo(p)
        return str(p)
    if kind == "dev-zero":
        p = tmp / ("zero" + suffix)
        p.symlink_to("/dev/zero")
        return str(p)
    if kind == "socket":
        p = tmp / ("sock" + suffix)
        s = socket.socket(socket.AF_UNIX)
        s.bind(str(p))
        s.close()
        return str(p)
    if kind == "folder":
        p = tmp / ("folder" + suffix)
        p.mkdir()
        return str(p)
    if kind == "nul-byte":
        return str(tmp / ("nul\0" + suffix))
    if kind == "loop":
        p = tmp / ("loop" + suffix)
        p.symlink_to(p)  # a plug-in's path resolved with Path.resolve raised RuntimeError
        return str(p)
    raise AssertionError(kind)


KINDS = (
    "too-long",
    "long-part-deep",
    "through-a-file",
    "dangling-link",
    "fifo",
    "dev-zero",
    "socket",
    "folder",
    "nul-byte",
    "loop",
)


def _sweep_with_base(tmp: Path, p: str) -> list[str]:
    f = tmp / "base.toml"
    f.write_text(f'name = "b"\nbase = {p!r}\n[axes]\nR2_ratio = [1.0]\n'.replace("'", '"'))
    return ["sweep", str(f), "--dry-run"]


def _compare_summary(tmp: Path, p: str) -> list[str]:
    """A result folder whose summary.json is the hostile path (a link to it)."""
    run = tmp / "result"
    run.mkdir()
    try:
        (run / "summary.json").symlink_to(p)
    except (OSError, ValueError):
        return ["compare", p]
    return ["compare", str(run)]


def _replay_map(tmp: Path, p: str) -> list[str]:
    rec = tmp / "rec.csv"
    rec.write_text("time_s\n0\n")
    return ["replay", str(rec), "--map", p, "--out", str(tmp / "o")]


#: every place a command reads a file or folder the user names: (command, suffix, argv)
READERS = {
    "run SCENARIO": ("run", ".toml", lambda t, p: ["run", p, "-q", "--out", str(t / "o")]),
    "run SUMMARY": ("run", ".json", lambda t, p: ["run", p, "-q", "--out", str(t / "o")]),
    "run machine.file": (
        "run",
        ".toml",
        lambda t, p: ["run", "sensorless", "-q", "--set", f"machine.file={p!r}".replace("'", '"')],
    ),
    "run plugins.modules": (
        "run",
        ".py",
        lambda t, p: [
            "run",
            "sensorless",
            "-q",
            "--allow-plugins",
            "--set",
            f"plugins.modules=[{p!r}]".replace("'", '"'),
        ],  # fmt: skip
    ),
    "show": ("show", ".toml", lambda t, p: ["show", p]),
    "sweep FILE": ("sweep", ".toml", lambda t, p: ["sweep", p, "--dry-run"]),
    "sweep base": ("sweep", ".toml", _sweep_with_base),
    "stability": ("stability", ".toml", lambda t, p: ["stability", p, "--out", str(t / "o")]),
    "bench-estimators --base": (
        "bench-estimators",
        ".toml",
        lambda t, p: ["bench-estimators", "--base", p, "--out", str(t / "o")],
    ),
    "commission": ("commission", ".toml", lambda t, p: ["commission", p, "--out", str(t / "o")]),
    "compare RUN_DIR": ("compare", "", lambda t, p: ["compare", p]),
    "compare summary.json": ("compare", ".json", _compare_summary),
    "replay RECORDING": ("replay", ".parquet", lambda t, p: ["replay", p, "--out", str(t / "o")]),
    "replay --map": ("replay", ".toml", _replay_map),
}

#: commands that read no file the user names
READS_NOTHING = {"presets", "fuzzy-table", "paper", "machine-from-nameplate", "warm-up"}


def test_every_command_is_either_a_reader_here_or_reads_nothing():
    import argparse

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    covered = {command for command, _, _ in READERS.values()}
    assert set(sub.choices) == covered | READS_NOTHING


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("reader", READERS)
def test_a_hostile_path_given_to_a_reader_is_bad_input_in_one_line(tmp_path, reader, kind):
    _, suffix, argv = READERS[reader]
    if kind == "folder" and reader == "compare RUN_DIR":
        pytest.skip("a folder is what compare reads (an empty one: covered elsewhere)")
    path = _hostile(tmp_path, kind, suffix)
    rc, err = _main(*argv(tmp_path, path))
    assert rc == 2, err
    lines = [x for x in err.strip().splitlines() if not x.startswith("imdrive: warning:")]
    assert len(lines) == 1 and lines[0].startswith("imdrive: error: "), err
    assert "Traceback" not in err and "Errno" not in err, err
    assert len(lines[0]) < 400, lines[0]  # a 300-character name is cut
    assert not (tmp_path / "o").exists()


def test_a_long_name_the_os_refuses_after_the_readers_is_still_bad_input(tmp_path, monkeypatch):
    """The command line's last resort: an OSError of a path's form on a path the user gave
    (here raised from deep inside a command) is exit 2, not the environment's exit 4."""
    import errno

    given = str(tmp_path / "x" / LONG)

    def boom(args):
        raise OSError(errno.ENAMETOOLONG, "File name too long", given)

    parser = build_parser()
    # main() takes its parser from the per-process cache (imdrive.cli._parser)
    monkeypatch.setattr("imdrive.cli._parser", lambda: _with_func(parser, "show", boom))
    rc, err = _main("show", given)
    assert rc == 2, err
    assert "a name longer than the file system allows" in err


def test_an_environment_error_on_the_users_path_stays_exit_4(tmp_path, monkeypatch):
    import errno

    given = str(tmp_path / "out")

    def full(args):
        raise OSError(errno.ENOSPC, "No space left on device", given + "/summary.json")

    parser = build_parser()
    monkeypatch.setattr("imdrive.cli._parser", lambda: _with_func(parser, "show", full))
    rc, err = _main("show", given)
    assert rc == 4, err
    assert "ENOSPC" in err


def _with_func(parser, command, func):
    import argparse

    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    sub.choices[command].set_defaults(func=func)
    return parser
