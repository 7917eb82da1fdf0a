"""One output rule for every command and function that writes (issue 40): each is tried with
the same hostile paths, and each refuses them with exit 2 (ConfigError in the API), one line
naming the flag, before any work, leaving what is there as it was. The commands are read from
the parser: a new command must be listed here as a writer or as one that writes nothing."""

from __future__ import annotations

import io
import os
import socket
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from imdrive.cli import build_parser, main
from imdrive.errors import ConfigError

LONG = "a" * 300
NAMEPLATE = [
    "--power-kw=2.2", "--voltage=400", "--frequency=50", "--poles=4", "--speed=1436",
    "--current=5", "--pf=0.79", "--efficiency=0.82",
]  # fmt: skip


def _main(*argv) -> tuple[int, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        rc = main(list(argv))
    return rc, err.getvalue()


def _folder_target(tmp: Path, kind: str) -> str:
    """A hostile ``--out`` for a command that writes a folder."""
    if kind == "empty":
        return ""
    if kind in (".", ".."):
        return kind
    if kind == "file":
        (tmp / "notes.txt").write_text("mine")
        return str(tmp / "notes.txt")
    if kind == "under-a-file":
        (tmp / "notes.txt").write_text("mine")
        return str(tmp / "notes.txt" / "sub")
    if kind == "fifo":
        os.mkfifo(tmp / "fifo")
        return str(tmp / "fifo")
    if kind == "socket":
        s = socket.socket(socket.AF_UNIX)
        s.bind(str(tmp / "sock"))
        s.close()
        return str(tmp / "sock")
    if kind == "device":
        return "/dev/null"  # the folder rule refuses it before anything is written
    if kind == "dangling-link":
        (tmp / "link").symlink_to(tmp / "nothing")
        return str(tmp / "link")
    if kind == "too-long":
        return str(tmp / LONG)
    if kind == "nul-byte":
        return str(tmp / "a\0b")
    if kind == "foreign-folder":
        (tmp / "thesis").mkdir()
        (tmp / "thesis" / "thesis.tex").write_text("mine")
        return str(tmp / "thesis")
    if kind == "link-to-foreign-folder":
        (tmp / "thesis").mkdir()
        (tmp / "thesis" / "thesis.tex").write_text("mine")
        (tmp / "link").symlink_to(tmp / "thesis")
        return str(tmp / "link")
    raise AssertionError(kind)


FOLDER_KINDS = (
    "empty", ".", "..", "file", "under-a-file", "fifo", "socket", "device", "dangling-link",
    "too-long", "nul-byte", "foreign-folder", "link-to-foreign-folder",
)  # fmt: skip


def _rec(tmp: Path) -> str:
    (tmp / "rec.csv").write_text("time_s\n0\n")
    return str(tmp / "rec.csv")


#: every command that writes a folder: argv given the tmp folder and the --out value
FOLDER_WRITERS = {
    "run": lambda t, o: ["run", "sensorless", "-q", "--out", o],
    "sweep": lambda t, o: ["sweep", "detuning-map", "-q", "--out", o],
    "stability": lambda t, o: ["stability", "sensorless", "--out", o],
    "bench-estimators": lambda t, o: ["bench-estimators", "--out", o],
    "compare": lambda t, o: ["compare", str(t / "no-such-run"), "--out", o],
    "paper": lambda t, o: ["paper", "--out", o],
    "replay": lambda t, o: ["replay", _rec(t), "--out", o],
    "commission": lambda t, o: ["commission", "sensorless", "--out", o],
}
#: every command that writes one file
FILE_WRITERS = {
    "machine-from-nameplate": lambda t, o: ["machine-from-nameplate", *NAMEPLATE, "--out", o],
}
#: commands that write nothing the user names (warm-up fills imdrive's own cache)
WRITES_NOTHING = {"show", "presets", "fuzzy-table", "warm-up"}


def test_every_command_is_classified():
    import argparse

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert set(sub.choices) == set(FOLDER_WRITERS) | set(FILE_WRITERS) | WRITES_NOTHING


def _snapshot(tmp: Path) -> dict:
    return {
        str(p.relative_to(tmp)): (p.read_bytes() if p.is_file() and not p.is_symlink() else None)
        for p in sorted(tmp.rglob("*"))
        if not p.is_fifo() and not p.is_socket()
    }


@pytest.mark.parametrize("kind", FOLDER_KINDS)
@pytest.mark.parametrize("command", FOLDER_WRITERS)
def test_a_hostile_out_folder_is_refused_before_any_work(tmp_path, monkeypatch, command, kind):
    monkeypatch.chdir(tmp_path)
    out = _folder_target(tmp_path, kind)
    argv = FOLDER_WRITERS[command](tmp_path, out)
    before = _snapshot(tmp_path)
    rc, err = _main(*argv)
    assert rc == 2, err
    lines = [x for x in err.strip().splitlines() if not x.startswith("imdrive: warning:")]
    assert len(lines) == 1 and lines[0].startswith("imdrive: error: --out: "), err
    assert _snapshot(tmp_path) == before  # nothing written, nothing replaced
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")


FILE_KINDS = (
    "empty", ".", "..", "folder", "under-a-file", "fifo", "socket", "dangling-link",
    "too-long", "nul-byte",
)  # fmt: skip


def _file_target(tmp: Path, kind: str) -> str:
    if kind == "folder":
        (tmp / "d").mkdir()
        return str(tmp / "d")
    return _folder_target(tmp, kind)


@pytest.mark.parametrize("kind", FILE_KINDS)
@pytest.mark.parametrize("command", FILE_WRITERS)
def test_a_hostile_out_file_is_refused_before_any_work(tmp_path, monkeypatch, command, kind):
    monkeypatch.chdir(tmp_path)
    out = _file_target(tmp_path, kind)
    before = _snapshot(tmp_path)
    rc, err = _main(*FILE_WRITERS[command](tmp_path, out))
    assert rc == 2, err
    assert err.strip().splitlines()[-1].startswith("imdrive: error: --out: "), err
    assert _snapshot(tmp_path) == before


# -- the Python API's single-file writers: the same rule (imdrive._io.output_file) -----------


class _Res:
    """Enough of a SimulationResult for the writers that refuse before reading it."""

    signals = {"time_s": [0.0, 1.0]}
    columns = ["time_s"]


def _api_writers():
    from imdrive.run.export import to_mat, to_parquet
    from imdrive.run.formats.csv import to_csv
    from imdrive.run.replay_report import write_figure, write_report
    from imdrive.run.report import write_run_report
    from imdrive.stability.plots import plot_map, plot_overlay

    return {
        "to_csv": to_csv,
        "to_parquet": to_parquet,
        "to_mat": to_mat,
        "write_run_report": write_run_report,
        "replay write_figure": write_figure,
        "replay write_report": write_report,
        "plot_map": plot_map,
        "plot_overlay": plot_overlay,
    }


@pytest.mark.parametrize("kind", FILE_KINDS)
@pytest.mark.parametrize("writer", list(_api_writers()))
def test_the_api_file_writers_follow_the_same_rule(tmp_path, monkeypatch, writer, kind):
    """A refused path raises ConfigError naming ``path`` and writes nothing. The result is a
    stand-in the writers cannot draw or tabulate: each checks the path before it reads it."""
    monkeypatch.chdir(tmp_path)
    out = _file_target(tmp_path, kind)
    before = _snapshot(tmp_path)
    with pytest.raises(ConfigError) as exc:
        _api_writers()[writer](_Res(), out)
    assert exc.value.field == "path"
    assert _snapshot(tmp_path) == before
