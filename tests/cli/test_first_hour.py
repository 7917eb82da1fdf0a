"""Issue 39's first-hour defects of the command line, each with its reproducer: a closed pipe
ends quietly, ``commission`` takes ``-q`` as ``run`` does."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from imdrive.cli import EXIT_CLOSED_PIPE, build_parser


def _with_stdout_closed(*argv) -> subprocess.CompletedProcess:
    """Run ``imdrive ARGV`` with a stdout whose reader is gone before the command starts (the
    worst case of ``| head``: every write fails), so that the outcome does not depend on the
    pipe's buffer or on timing."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        return subprocess.run(
            [sys.executable, "-m", "imdrive", *argv],
            stdout=write_end,
            stderr=subprocess.PIPE,
            text=True,
            timeout=120,
        )
    finally:
        os.close(write_end)


@pytest.mark.slow  # 1.5 s or more on 2 cores (1.6-3.4 s measured 2026-11-29)
@pytest.mark.parametrize("argv", [["presets"], ["show", "sensorless"], ["fuzzy-table"]])
def test_a_closed_stdout_ends_quietly_with_141(argv):
    """``imdrive presets | head -2`` printed ``imdrive: error: I/O error: Broken pipe`` and
    exited 4 (issue 39)."""
    proc = _with_stdout_closed(*argv)
    assert proc.returncode == EXIT_CLOSED_PIPE == 141, proc.stderr
    assert proc.stderr == ""  # no "imdrive: error", no "Exception ignored", no traceback


def test_help_into_a_closed_pipe_is_quiet_too():
    """argparse writes a --help whatever becomes of it and exits 0; nothing else must fail on
    the closed stdout afterwards (the interpreter's last flush)."""
    proc = _with_stdout_closed("run", "--help")
    assert proc.returncode == 0 and proc.stderr == ""


def test_the_exit_code_table_lists_the_closed_pipe():
    assert "141" in build_parser().epilog


def test_commission_takes_quiet_as_run_does():
    parser = build_parser()
    for command in ("run", "commission"):
        argv = [command, "sensorless", "--out", "o"]
        assert parser.parse_args([*argv, "-q"]).quiet is True, command
        assert parser.parse_args([*argv, "--quiet"]).quiet is True, command
        assert parser.parse_args(argv).quiet is False, command


def test_every_command_that_compiles_takes_quiet():
    """Every command that runs the kernels (and may meet a cold cache, with its compile
    notice) takes ``-q``; ``imdrive paper`` did not."""
    parser = build_parser()
    argvs = {
        "paper": ["paper", "--out", "o"],
        "sweep": ["sweep", "detuning-map"],
        "stability": ["stability", "sensorless", "--out", "o"],
        "bench-estimators": ["bench-estimators", "--out", "o"],
        "replay": ["replay", "rec", "--out", "o"],
        "warm-up": ["warm-up"],
    }
    for command, argv in argvs.items():
        assert parser.parse_args([*argv, "-q"]).quiet is True, command
        assert parser.parse_args(argv).quiet is False, command


def test_paper_quiet_prints_nothing(tmp_path, monkeypatch, capsys):
    """``imdrive paper -q``: the files, no progress and no summary (run_all stubbed: the
    reproduction itself is tested in tests/studies)."""
    from imdrive.studies import paper

    seen = {}

    def fake_run_all(out, progress=None):
        seen["progress"] = progress
        if progress is not None:
            progress("a step")
        out.mkdir(parents=True, exist_ok=True)
        (out / "results.json").write_text("{}")
        return {"compensation": []}

    monkeypatch.setattr(paper, "run_all", fake_run_all)
    from imdrive.cli import main

    rc = main(["paper", "--out", str(tmp_path / "p"), "-q"])
    assert rc == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    assert err == ""
    assert seen["progress"] is not None  # a silent progress, not the default bar
