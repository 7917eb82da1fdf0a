"""The ``imdrive`` command: outputs of a run, ``presets``, ``show``, and bad input.

Bad input must give ONE line on stderr naming the field and the rule, exit code 2, no traceback,
and nothing written to ``--out``. One case of each kind (a rule, a type, an unknown key, bad
TOML, a binary file, bad syntax) runs the real command in a subprocess
(``python -m imdrive``), the way a user meets them; the other values run the same ``main`` in
this process (1.5-4 s less each on 2 cores: the interpreter's start and imports), where a
traceback would be an exception and a warning a second line of stderr.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from data.inprocess import imdrive_here

import imdrive
from imdrive.cli import main
from imdrive.config.presets import preset_names, preset_text
from imdrive.config.scenario import Scenario

REQUIRED_COLUMNS = (
    "time_s speed_rpm w_m_rad_s torque_Nm load_torque_Nm i_a_A i_b_A i_c_A i_alpha_A i_beta_A "
    "psi_r_alpha_Wb psi_r_beta_Wb v_alpha_V v_beta_V R1_ohm R2_ohm"
).split()


def _imdrive(*args, cwd=None, timeout=300):
    return subprocess.run(
        [sys.executable, "-m", "imdrive", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=timeout,
    )


def _nothing_written(out: Path) -> bool:
    return not out.exists() or (out.is_dir() and not any(out.iterdir()))


# ------------------------------------------------------------------------------------------
# a run


def _short_run(tmp: Path, run=imdrive_here):
    out = tmp / "fa"
    proc = run(
        "run", "free-acceleration", "--out", out, "--set", "simulation.t_end_s=0.05", cwd=tmp
    )
    return proc, out, tmp


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    """The run whose files the fast tests read, through ``main`` in this process
    (``data.inprocess``: an interpreter's start and the cached drive's load are 5-9 s)."""
    return _short_run(tmp_path_factory.mktemp("run"))


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_run_exit_code_and_files(tmp_path):
    """The same run through the real command: exit code, files, nothing left behind."""
    proc, out, tmp = _short_run(tmp_path, run=_imdrive)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout
    names = {p.name for p in out.iterdir()}
    assert {"timeseries.csv", "summary.json"} <= names
    pngs = sorted(out.glob("*.png"))
    assert pngs, names
    for p in pngs:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", p.name
    assert not any(n.startswith(".partial") for n in names)  # no leftover temporary folder
    assert not (tmp / "out").exists()  # --out was honoured, nothing in the default place


def test_run_timeseries_csv(short_run):
    _, out, _ = short_run
    with open(out / "timeseries.csv") as fh:
        header = fh.readline().strip().split(",")
    for col in REQUIRED_COLUMNS:
        assert col in header, col
    data = np.loadtxt(out / "timeseries.csv", delimiter=",", skiprows=1)
    assert data.shape == (501, len(header))  # t = 0 .. 0.05 s every 100 us
    col = {name: data[:, k] for k, name in enumerate(header)}
    np.testing.assert_allclose(col["time_s"], np.arange(501) * 1e-4, atol=1e-12)
    assert np.all(np.isfinite(data))
    np.testing.assert_allclose(col["i_a_A"], col["i_alpha_A"], rtol=1e-8, atol=1e-7)
    np.testing.assert_allclose(col["i_a_A"] + col["i_b_A"] + col["i_c_A"], 0.0, atol=1e-6)
    np.testing.assert_allclose(col["speed_rpm"], col["w_m_rad_s"] * 30 / math.pi, rtol=1e-7)
    assert col["speed_rpm"][-1] > 100.0  # it accelerates
    np.testing.assert_allclose(col["R1_ohm"], 0.435)
    np.testing.assert_allclose(col["R2_ohm"], 0.816)
    np.testing.assert_allclose(np.hypot(col["v_alpha_V"], col["v_beta_V"]), 179.6, rtol=1e-3)


def test_run_summary_json(short_run):
    _, out, _ = short_run
    s = json.loads((out / "summary.json").read_text())
    # the scenario as run, complete and reloadable
    assert s["scenario"]["name"] == "free-acceleration"
    assert s["scenario"]["simulation"]["t_end_s"] == 0.05
    assert s["scenario"]["machine"]["R1_ohm"] == 0.435
    expected = Scenario.read("free-acceleration", ["simulation.t_end_s=0.05"])
    assert Scenario.from_dict(s["scenario"]) == expected
    # versions
    assert s["versions"]["imdrive"] == imdrive.__version__
    for pkg in ("python", "numpy", "scipy", "numba"):
        assert s["versions"][pkg]
    # final values equal the last row of the CSV
    data = np.loadtxt(out / "timeseries.csv", delimiter=",", skiprows=1)
    header = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    for k, name in enumerate(header):
        assert s["final"][name] == pytest.approx(data[-1, k], rel=1e-7, abs=1e-9), name
    # wall time and status
    assert s["wall_time_s"] > 0
    assert s["simulated_time_s"] == pytest.approx(0.05)
    assert s["diverged"] is False


def test_run_in_process_with_capsys(tmp_path, capsys):
    out = tmp_path / "o"
    rc = main(
        [
            "run",
            "free-acceleration",
            "--out",
            str(out),
            "--set",
            "simulation.t_end_s=0.01",
            "--set",
            "output.figures=false",
        ]
    )
    cap = capsys.readouterr()
    assert rc == 0, cap.err
    # report.html is on by default (output.report)
    assert sorted(p.name for p in out.iterdir()) == [
        "report.html",
        "summary.json",
        "timeseries.csv",
    ]
    assert "final speed" in cap.err


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_presets():
    proc = _imdrive("presets")
    assert proc.returncode == 0, proc.stderr
    for name in preset_names():
        assert name in proc.stdout
    assert "free-acceleration" in proc.stdout
    assert "paper-table-iv" in proc.stdout and "krause-3hp" in proc.stdout


def test_show(capsys):
    assert main(["show", "free-acceleration"]) == 0
    text = capsys.readouterr().out
    # the preset's file after the comment that says its drive mode
    assert text == "# drive mode: open-loop" + text.split("# drive mode: open-loop", 1)[1]
    assert text.endswith(preset_text("free-acceleration"))
    # what show prints is a valid scenario file
    assert Scenario.from_toml(text) == Scenario.read("free-acceleration")


def test_show_unknown_preset(capsys):
    assert main(["show", "no-such-preset"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "no-such-preset" in err


# ------------------------------------------------------------------------------------------
# bad input

BAD_SET = [
    # (--set value, field named in the message, words of the rule)
    ("machine.R1_ohm=0", "machine.R1_ohm", "> 0"),
    ("machine.R2_ohm=-0.8", "machine.R2_ohm", "> 0"),
    ("machine.Ll1_H=0", "machine.Ll1_H", "> 0"),
    ("machine.Ll2_H=-1e-3", "machine.Ll2_H", "> 0"),
    ("machine.M_H=0", "machine.M_H", "> 0"),
    ("machine.J_kgm2=0", "machine.J_kgm2", "> 0"),
    ("machine.J_kgm2=-0.1", "machine.J_kgm2", "> 0"),
    ("simulation.Ts_s=0", "simulation.Ts_s", "> 0"),
    ("simulation.Ts_s=-1e-4", "simulation.Ts_s", "> 0"),
    ("simulation.substeps=0", "simulation.substeps", ">= 1"),
    ("simulation.substeps=-3", "simulation.substeps", ">= 1"),
    ("simulation.substeps=1.5", "simulation.substeps", "integer"),
    ("simulation.substeps=abc", "simulation.substeps", "integer"),
    ("machine.R1_ohm=true", "machine.R1_ohm", "number"),
    ("machine.R1_ohm=abc", "machine.R1_ohm", "number"),
    ("simulation.t_end_s=[1, 2]", "simulation.t_end_s", "number"),
    ("load.torque_Nm=nan", "load.torque_Nm", "finite"),
    ("output.figures=1", "output.figures", "true or false"),
    ("drive.mode=sideways", "drive.mode", "must be one of"),
    ("simulation.bogus=1", "simulation.bogus", "no such setting"),
    ("machine.bogus=1", "machine.bogus", "no such setting"),
    ("nosection.key=1", "nosection.key", "no such setting"),
    ("simulation.t_end_s.deeper=1", "simulation.t_end_s.deeper", "no such setting"),
    ("simulation=1", "simulation", "no such setting"),
    ("plant.thermal.tau1_s=0", "plant.thermal.tau1_s", "> 0"),
    ("machine.pole_pairs=0", "machine.pole_pairs", ">= 1"),
    ("machine.preset=no-such-machine", "machine.preset", "unknown preset"),
]


def _assert_bad_input(proc, out: Path, field: str, rule: str):
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    assert "Traceback" not in proc.stderr and "Traceback" not in proc.stdout
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert field in lines[0], lines[0]
    assert rule in lines[0], lines[0]
    assert _nothing_written(out), list(out.iterdir())


#: the --set values also run in a subprocess: a rule, a type, an unknown key
BAD_SET_SUBPROCESS = ("machine.R1_ohm=0", "simulation.substeps=abc", "nosection.key=1")


@pytest.mark.parametrize(("setting", "field", "rule"), BAD_SET, ids=[b[0] for b in BAD_SET])
def test_bad_set(tmp_path, setting, field, rule):
    out = tmp_path / "out"
    proc = imdrive_here("run", "free-acceleration", "--out", out, "--set", setting, cwd=tmp_path)
    _assert_bad_input(proc, out, field, rule)
    assert not (tmp_path / "out" / "free-acceleration").exists()


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@pytest.mark.parametrize("setting", BAD_SET_SUBPROCESS)
def test_bad_set_from_the_real_command(tmp_path, setting):
    _, field, rule = next(b for b in BAD_SET if b[0] == setting)
    out = tmp_path / "out"
    proc = _imdrive("run", "free-acceleration", "--out", out, "--set", setting, cwd=tmp_path)
    _assert_bad_input(proc, out, field, rule)
    assert not (tmp_path / "out" / "free-acceleration").exists()


def test_bad_input_into_existing_empty_folder(tmp_path):
    out = tmp_path / "existing"
    out.mkdir()
    proc = imdrive_here(
        "run", "free-acceleration", "--out", out, "--set", "machine.M_H=-1", cwd=tmp_path
    )
    _assert_bad_input(proc, out, "machine.M_H", "> 0")


GOOD = """
name = "custom"
[machine]
preset = "paper-table-iv"
[simulation]
t_end_s = 0.01
"""

BAD_FILES = {
    # name: (file text or bytes, field, rule)
    "unknown-key": (GOOD + "substepz = 2\n", "simulation.substepz", "unknown key"),
    "unknown-section": (GOOD + "[plantt]\nspeed_mode = 'imposed'\n", "plantt", "unknown key"),
    "unknown-machine-key": (
        GOOD.replace('preset = "paper-table-iv"', "R3_ohm = 1.0"),
        "machine.R3_ohm",
        "unknown key",
    ),
    "unknown-top-level": ("foo = 1\n" + GOOD, "foo", "unknown key"),
    "wrong-type": (GOOD + 'Ts_s = "fast"\n', "simulation.Ts_s", "number"),
    "wrong-type-bool": (GOOD + "substeps = true\n", "simulation.substeps", "integer"),
    "section-not-table": ('load = 5\nname = "x"\n', "load", "table"),
    "zero-resistance": (
        GOOD.replace("[simulation]", "R2_ohm = 0.0\n[simulation]"),
        "R2_ohm",
        "> 0",
    ),
    "negative-inertia": (
        GOOD.replace("[simulation]", "J_kgm2 = -1.0\n[simulation]"),
        "machine.J_kgm2",
        "> 0",
    ),
    "bad-profile": (
        GOOD + "[plant]\nR2_scale = { initial = 1.0, changes = [{ at = 1.0 }] }\n",
        "plant.R2_scale.changes[0]",
        "needs 'at' and 'to'",
    ),
    "malformed-toml": ('name = "x"\n[simulation\nt_end_s = 1\n', "scenario", "invalid TOML"),
    "malformed-toml-value": ("[simulation]\nt_end_s = 1.0.0\n", "scenario", "invalid TOML"),
    "duplicate-key": ("[simulation]\nt_end_s = 1\nt_end_s = 2\n", "scenario", "invalid TOML"),
    # a binary / non-UTF-8 file is malformed TOML too
    "not-utf8": (b"\xff\xfe[simulation]\x00\n", "scenario", ""),
}


#: the bad files also run in a subprocess: an unknown key, malformed TOML, a binary file
BAD_FILES_SUBPROCESS = ("unknown-key", "malformed-toml", "not-utf8")


def _bad_file(tmp_path: Path, case: str) -> Path:
    text, _, _ = BAD_FILES[case]
    path = tmp_path / "scenario.toml"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    return path


@pytest.mark.parametrize("case", list(BAD_FILES))
def test_bad_scenario_file(tmp_path, case):
    _, field, rule = BAD_FILES[case]
    out = tmp_path / "out"
    proc = imdrive_here("run", _bad_file(tmp_path, case), "--out", out, cwd=tmp_path)
    _assert_bad_input(proc, out, field, rule)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@pytest.mark.parametrize("case", BAD_FILES_SUBPROCESS)
def test_bad_scenario_file_from_the_real_command(tmp_path, case):
    _, field, rule = BAD_FILES[case]
    out = tmp_path / "out"
    proc = _imdrive("run", _bad_file(tmp_path, case), "--out", out, cwd=tmp_path)
    _assert_bad_input(proc, out, field, rule)


def test_good_scenario_file_runs(tmp_path):
    """The template the bad files are made from is itself valid (so each bad file has one fault)."""
    path = tmp_path / "scenario.toml"
    path.write_text(GOOD + "[output]\nfigures = false\n")
    out = tmp_path / "out"
    rc = main(["run", str(path), "--out", str(out), "-q"])
    assert rc == 0
    assert (out / "summary.json").exists()


BAD_SYNTAX = [
    (["run", "no-such-preset"], "scenario", "neither a preset"),
    (["run", "./missing/file.toml"], "scenario", "neither a preset"),
    (["run", "free-acceleration", "--set", "simulation.t_end_s"], "simulation.t_end_s", "="),
    (["run", "free-acceleration", "--set", "=3"], "--set", "key before"),
]


@pytest.mark.parametrize(("args", "field", "rule"), BAD_SYNTAX)
def test_bad_preset_or_override_syntax(tmp_path, args, field, rule):
    out = tmp_path / "out"
    proc = imdrive_here(*args, "--out", out, cwd=tmp_path)
    _assert_bad_input(proc, out, field, rule)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@pytest.mark.parametrize(("args", "field", "rule"), BAD_SYNTAX[::3])
def test_bad_preset_or_override_syntax_from_the_real_command(tmp_path, args, field, rule):
    out = tmp_path / "out"
    proc = _imdrive(*args, "--out", out, cwd=tmp_path)
    _assert_bad_input(proc, out, field, rule)


def test_scenario_path_is_a_folder(tmp_path):
    folder = tmp_path / "adir.toml"
    folder.mkdir()
    out = tmp_path / "out"
    proc = imdrive_here("run", folder, "--out", out, cwd=tmp_path)
    _assert_bad_input(proc, out, "scenario", "is a folder, not a regular file")


def test_out_is_a_file(tmp_path):
    out = tmp_path / "afile"
    out.write_text("keep me")
    proc = imdrive_here(
        "run", "free-acceleration", "--out", out, "--set", "simulation.t_end_s=0.01", cwd=tmp_path
    )
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert "--out" in proc.stderr
    assert out.read_text() == "keep me"


def test_bad_input_in_process(tmp_path, capsys):
    """The same rule through main() directly: return code 2, one line, the field named."""
    out = tmp_path / "out"
    rc = main(["run", "free-acceleration", "--out", str(out), "--set", "machine.Ll1_H=-2e-3"])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and "machine.Ll1_H" in err and "> 0" in err
    assert _nothing_written(out)


def test_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["frobnicate"])
    assert exc.value.code == 2
    with pytest.raises(SystemExit) as exc:
        main([])
    assert exc.value.code == 2
