"""Issue 40 (reliability and security, round 4), each class with its reproducer: what a
command writes (one file, one folder) follows one checked rule validated before any work;
extreme flag values and contradictory derived values are bad input (exit 2, one line naming
the field, nothing written); every command's --help works. None of these simulates a drive."""

from __future__ import annotations

import io
import json
import os
import stat
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from imdrive import Scenario
from imdrive.cli import build_parser, main
from imdrive.errors import ConfigError

NAMEPLATE = {
    "--power-kw": "2.2",
    "--voltage": "400",
    "--frequency": "50",
    "--poles": "4",
    "--speed": "1436",
    "--current": "5",
    "--pf": "0.79",
    "--efficiency": "0.82",
}


def _main(*argv) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        rc = main(list(argv))
    return rc, out.getvalue(), err.getvalue()


def _one_line(err: str) -> str:
    lines = [x for x in err.strip().splitlines() if x.startswith("imdrive: error:")]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def _nameplate(*extra, **changes) -> list[str]:
    args = dict(NAMEPLATE)
    args.update(changes)
    return ["machine-from-nameplate", *(f"{k}={v}" for k, v in args.items()), *extra]


# ------------------------------------------------------------------------------------------
# class 12: every command's --help


def _commands(parser, prefix=()) -> list[tuple[str, ...]]:
    """Every command path of the parser, sub-commands of sub-commands included, read from the
    argparse parser itself so that a new command is covered without editing this list."""
    import argparse

    found = [prefix]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                found += _commands(child, (*prefix, name))
    return found


COMMAND_PATHS = _commands(build_parser())


def test_the_command_list_is_read_from_the_parser():
    assert len(COMMAND_PATHS) > 10 and ("machine-from-nameplate",) in COMMAND_PATHS


@pytest.mark.parametrize("path", COMMAND_PATHS, ids=lambda p: " ".join(p) or "imdrive")
def test_every_commands_help_prints(path):
    """``imdrive ... --help``: exit 0, the usage on stdout, nothing on stderr (issue 39: the
    ``%`` of machine-from-nameplate's help ended in a traceback)."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err), pytest.raises(SystemExit) as exc:
        main([*path, "--help"])
    assert exc.value.code == 0, err.getvalue()
    assert err.getvalue() == ""
    assert out.getvalue().startswith(f"usage: {' '.join(('imdrive', *path))} ")
    if path == ("machine-from-nameplate",):
        assert "not %" in out.getvalue()  # its efficiency text, the % that crashed it


# ------------------------------------------------------------------------------------------
# class 2: machine-from-nameplate --out, one file by the rule


def test_nameplate_out_refuses_special_files_and_folders(tmp_path):
    (tmp_path / "dir").mkdir()
    (tmp_path / "file").write_text("mine")
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "dangling").symlink_to(tmp_path / "nothing.toml")
    cases = {
        "/dev/null": "character device",
        str(tmp_path / "fifo"): "FIFO",
        str(tmp_path / "dir"): "folder",
        str(tmp_path) + "/.": "folder",
        "..": "folder",
        "": "empty",
        str(tmp_path / "dangling"): "link to nothing",
        str(tmp_path / "file" / "sub.toml"): "which is a file",
        str(tmp_path / "nodir" / "m.toml"): "not an existing folder",
        str(tmp_path / ("x" * 300)): "longer than 255 bytes",
    }
    for out, words in cases.items():
        rc, stdout, err = _main(*_nameplate("--out", out))
        assert rc == 2, (out, err)
        line = _one_line(err)
        assert line.startswith("imdrive: error: --out:") and words in line, (out, line)
        assert stdout == ""
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    assert stat.S_ISFIFO(os.stat(tmp_path / "fifo").st_mode)
    assert (tmp_path / "file").read_text() == "mine"
    assert not (tmp_path / "nothing.toml").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dangling", "dir", "fifo", "file"]
    assert list((tmp_path / "dir").iterdir()) == []


def test_nameplate_out_writes_through_a_symlink_and_atomically(tmp_path):
    target = tmp_path / "machines" / "m1.toml"
    target.parent.mkdir()
    target.write_text("old")
    link = tmp_path / "motor.toml"
    link.symlink_to(target)
    rc, _, err = _main(*_nameplate("--out", str(link)))
    assert rc == 0, err
    assert link.is_symlink() and link.resolve() == target.resolve()
    assert target.read_text().startswith("# An induction machine estimated")
    # written beside the target and renamed: no temporary file left in either folder
    assert sorted(p.name for p in target.parent.iterdir()) == ["m1.toml"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["machines", "motor.toml"]


# ------------------------------------------------------------------------------------------
# class 4: extreme values on the nameplate's flags


@pytest.mark.parametrize(
    "flag, value",
    [
        ("--power-kw", "1e-300"),
        ("--voltage", "1e151"),
        ("--pf", "1e-300"),
        ("--efficiency", "1e-300"),
        ("--breakdown-ratio", "inf"),
        ("--breakdown-ratio", "1e300"),
        ("--starting-current-ratio", "inf"),
        ("--J", "inf"),
        ("--current", "1e-100"),
    ],
)
def test_nameplate_reproducers_exit_2_naming_the_flag(tmp_path, flag, value):
    out = tmp_path / "m.toml"
    rc, _, err = _main(*_nameplate("--out", str(out)), f"{flag}={value}")
    assert rc == 2, err
    assert _one_line(err).startswith("imdrive: error: --")
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_nameplate_every_flag_over_extreme_values_is_clean(tmp_path):
    """Every numeric flag over vanishing, huge and non-finite values: 0 with a file, or 2
    with one line and nothing written; never 5 (ZeroDivisionError, OverflowError)."""
    out = tmp_path / "m.toml"
    flags = [f for f in NAMEPLATE if f != "--poles"] + [
        "--breakdown-ratio",
        "--starting-current-ratio",
        "--J",
        "--core-loss-fraction",
        "--mechanical-loss-fraction",
        "--stray-loss-fraction",
    ]
    values = ["0", "-1", "5e-324", "1e-300", "1e-150", "1e-20", "1e20", "1e150", "1e300"]
    values += ["inf", "-inf", "nan", "1.0000001"]
    for flag in flags:
        for v in values:
            extra = ["--method=lee"] if flag.endswith("fraction") else []
            rc, _, err = _main(*_nameplate("--out", str(out), *extra), f"{flag}={v}")
            assert rc in (0, 2), (flag, v, err)
            if rc == 2:
                _one_line(err)
                assert not out.exists(), (flag, v)
            out.unlink(missing_ok=True)


# ------------------------------------------------------------------------------------------
# class 4: stability axes far outside the machine


@pytest.mark.parametrize(
    "flag, value",
    [("--speeds", "0:1e308:2"), ("--speeds=-1e6:0:2", None), ("--torques", "0:1e300:2")],
)
def test_stability_axes_beyond_the_machine_are_bad_input(tmp_path, flag, value):
    out = tmp_path / "st"
    argv = ["stability", "sensorless", "--out", str(out), flag] + ([value] if value else [])
    rc, _, err = _main(*argv)
    assert rc == 2, err
    assert _one_line(err).startswith(f"imdrive: error: {flag.split('=')[0]}:")
    assert not out.exists()


# ------------------------------------------------------------------------------------------
# class 5: derived values held to the rules of given ones


def test_a_rated_torque_giving_a_speed_above_synchronous_is_refused(tmp_path):
    with pytest.raises(ConfigError) as exc:
        Scenario.read("sensorless", ["machine.rated_torque_Nm=1"])
    assert exc.value.field == "machine.rated_torque_Nm"
    assert "synchronous" in exc.value.rule
    out = tmp_path / "o"
    rc, _, err = _main(
        "run", "sensorless", "--set", "machine.rated_torque_Nm=1", "--out", str(out), "-q"
    )
    assert rc == 2 and "machine.rated_torque_Nm" in _one_line(err)
    assert not out.exists()
    # a rated torque above P / w_sync still derives a speed below synchronous
    sc = Scenario.read("sensorless", ["machine.rated_torque_Nm=12.5"])
    from imdrive.config.machine import rated_point

    rp = rated_point(sc.machine)
    assert 0 < rp.speed_rpm < rp.synchronous_speed_rpm


# ------------------------------------------------------------------------------------------
# class 3: commission --out, the folder rule of run/sweep/stability, before the run


def _commission(out: str, *extra) -> tuple[int, str]:
    rc, _, err = _main("commission", "sensorless-realistic", "--out", out, *extra)
    return rc, err


def test_commission_out_is_checked_before_the_identification_run(tmp_path, monkeypatch):
    """Every refusal comes before a test runs: ``identify`` would fail the test."""
    import imdrive.commission as com

    def _no_run(*a, **k):
        raise AssertionError("the identification run started")

    monkeypatch.setattr(com, "identify", _no_run)
    foreign = tmp_path / "thesis"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("mine")
    (tmp_path / "to-thesis").symlink_to(foreign)
    (tmp_path / "file").write_text("mine")
    (tmp_path / "dangling").symlink_to(tmp_path / "nothing")
    monkeypatch.chdir(tmp_path)
    cases = {
        str(foreign): "thesis.tex",
        str(tmp_path / "to-thesis"): "thesis.tex",
        ".": "current folder",
        "..": "current folder",
        "": "empty",
        str(tmp_path / "file"): "not a folder",
        str(tmp_path / "file" / "sub"): "which is a file",
        str(tmp_path / "dangling"): "link to nothing",
        "c" * 300: "longer than 255 bytes",
    }
    for out, words in cases.items():
        rc, err = _commission(out)
        assert rc == 2, (out, err)
        line = _one_line(err)
        assert line.startswith("imdrive: error: --out:") and words in line, (out, line)
    assert sorted(p.name for p in foreign.iterdir()) == ["thesis.tex"]
    assert (tmp_path / "file").read_text() == "mine"
    # the API applies the same rule
    with pytest.raises(ConfigError, match="thesis.tex"):
        com.commission(Scenario.read("sensorless-realistic"), foreign)
    with pytest.raises(ConfigError, match="^scenario: must be a Scenario"):
        com.commission(None)


def test_commission_folder_is_replaced_whole_and_a_failed_write_keeps_the_old(
    tmp_path, monkeypatch
):
    """The outputs are staged and swapped in: a second commissioning that dies while it draws
    its figures leaves the first one's folder as it was, never a mix of the two."""
    import importlib

    import imdrive.commission.figures as figs

    # the package's name "identify" is the function: the module through importlib
    ident = importlib.import_module("imdrive.commission.identify")

    sc = Scenario.read("sensorless-realistic")

    class _Res:
        def summary(self):
            return {"identified": {"R1_ohm": 1.0}}

    monkeypatch.setattr(ident, "identified_scenario", lambda sc, res: sc.to_dict())
    out = tmp_path / "c"

    def _figures(res, folder):
        (Path(folder) / "dc.png").write_bytes(b"new")

    monkeypatch.setattr(figs, "save_figures", _figures)
    ident.write_outputs(sc, _Res(), out)
    first = {p.name: p.read_bytes() for p in out.iterdir()}
    assert set(first) == {"dc.png", "summary.json", "identified.toml"}

    def _dies(res, folder):
        (Path(folder) / "dc.png").write_bytes(b"second")
        raise KeyboardInterrupt  # killed while drawing

    monkeypatch.setattr(figs, "save_figures", _dies)
    with pytest.raises(KeyboardInterrupt):
        ident.write_outputs(sc, _Res(), out)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c"]  # no staging left
    assert json.loads((out / "summary.json").read_text())["identified"] == {"R1_ohm": 1.0}


# -- class 10: a summary.json path is checked before it is opened ---------------------------


@pytest.mark.slow  # 1.5 s or more on 2 cores (a subprocess each: 1.7-4 s measured 2026-11-29)
@pytest.mark.parametrize("kind", ["fifo", "dev-zero", "too-big"])
def test_a_special_or_huge_summary_json_is_refused_without_reading_it(tmp_path, kind):
    import subprocess
    import sys

    path = tmp_path / "summary.json"
    if kind == "fifo":
        os.mkfifo(path)  # opening it would block until a writer comes: the run hung
    elif kind == "dev-zero":
        path.symlink_to("/dev/zero")  # read to the end: memory ran out
    else:
        with open(path, "wb") as f:  # sparse: 65 MB that take no disk
            f.truncate(65 * 1024**2)
    res = subprocess.run(
        [sys.executable, "-m", "imdrive", "run", str(path), "-q", "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "summary.json" in lines[0], lines
    assert ("not a regular file" if kind != "too-big" else "bytes") in lines[0]
    assert not (tmp_path / "o").exists()
