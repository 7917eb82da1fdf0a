"""The command line's help for users: examples, "did you mean", ``show --all``, default folders,
timing lines; and the scenario's TOML writer and summary.json re-runs behind them."""

from __future__ import annotations

import json
import tomllib

import pytest

import imdrive as im
from imdrive.cli import build_parser, main
from imdrive.config.presets import preset_names


@pytest.mark.parametrize(
    "command",
    ["run", "presets", "show", "paper", "fuzzy-table", "sweep", "stability", "bench-estimators"],
)
def test_every_subcommand_help_has_a_description_and_examples(command, capsys):
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args([command, "--help"])
    assert exc.value.code == 0
    text = capsys.readouterr().out
    assert "examples:" in text and f"imdrive {command}" in text.split("examples:")[1]


@pytest.mark.parametrize(
    ("argv", "suggestion"),
    [
        (["run", "sensorles"], "did you mean 'sensorless'?"),
        (["show", "paper-fig55"], "did you mean 'paper-fig5'?"),
        (["run", "sensorless", "--set", "simulation.t_end_z=1"], "'simulation.t_end_s'"),
        (["sweep", "detunin-map"], "did you mean 'detuning-map'?"),
    ],
)
def test_typos_get_a_suggestion_on_the_one_error_line(argv, suggestion, capsys, tmp_path):
    assert main([*argv, "--out", str(tmp_path / "o")] if argv[0] != "show" else argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("imdrive: error: ")
    assert suggestion in lines[0]


def test_key_typo_in_a_file_is_suggested(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text('name = "x"\n[simulation]\nt_end_s = 0.01\nsubstepz = 2\n')
    assert main(["run", str(f), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "simulation.substepz: unknown key; did you mean 'simulation.substeps'?" in err


@pytest.mark.parametrize("name", preset_names())
def test_to_toml_reads_back_to_the_same_scenario(name):
    sc = im.Scenario.read(name)
    assert im.Scenario.from_toml(sc.to_toml()) == sc


def test_show_all_lists_every_key_with_its_default(capsys):
    assert main(["show", "free-acceleration", "--all"]) == 0
    data = tomllib.loads(capsys.readouterr().out)
    assert data["simulation"]["Ts_s"] == 100e-6
    assert "report" in data["output"]  # a key the preset file does not set
    assert data["machine"]["R1_ohm"] > 0


def test_run_file_defaults_to_the_file_name_and_reruns_summary(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    text = im.Scenario.read("free-acceleration").with_overrides(
        {"simulation.t_end_s": 0.02, "output.figures": False, "output.report": False}
    )
    (tmp_path / "my-file.toml").write_text(text.to_toml())
    assert main(["run", "my-file.toml"]) == 0
    err = capsys.readouterr().err
    assert (tmp_path / "out" / "my-file" / "summary.json").exists()  # not out/free-acceleration
    assert "done in" in err and " s (simulation " in err
    summary = tmp_path / "out" / "my-file" / "summary.json"
    assert main(["run", str(summary), "--out", "again", "--set", "simulation.t_end_s=0.01"]) == 0
    again = json.loads((tmp_path / "again" / "summary.json").read_text())
    assert again["simulated_time_s"] == pytest.approx(0.01)
    assert main(["run", str(summary), "--set", "simulation.t_end_s=0.01"]) == 0
    assert (tmp_path / "out" / "my-file-rerun" / "summary.json").exists()  # not over the first
    first = json.loads(summary.read_text())
    first["scenario"]["simulation"]["t_end_s"] = 0.01
    assert again["scenario"] == first["scenario"]


def test_sweep_prints_a_start_line_when_not_on_a_terminal(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text(
        'name = "ux"\nbase = "free-acceleration"\n[set]\nsimulation.t_end_s = 0.02\n'
        '[axes]\n"machine.J_kgm2" = [0.05, 0.1]\n'
    )
    assert main(["sweep", str(f), "--out", str(tmp_path / "st"), "--no-figures"]) == 0
    err = capsys.readouterr().err
    assert "imdrive: sweep ux: 2 runs in 1 chunks of 32 (0 done)" in err
