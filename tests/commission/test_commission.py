"""The identification run: bad input, a failing test, and accuracy on the realistic drive."""

from __future__ import annotations

import json
import tomllib

import pytest

from imdrive.cli import main
from imdrive.commission import CommissioningFailed, commission
from imdrive.commission import dc as dc_module
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError


def test_open_loop_scenario_is_refused_in_one_line():
    with pytest.raises(ConfigError, match="drive.mode"):
        commission(Scenario.read("sensorless-realistic", ['drive.mode="open-loop"']))


def test_a_dc_link_too_low_is_refused_naming_it():
    with pytest.raises(ConfigError, match="inverter.Vdc_V"):
        commission(Scenario.read("sensorless-realistic", ["inverter.Vdc_V=100"]))


def test_cli_open_loop_exits_2_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "x"
    args = ["commission", "sensorless-realistic", "--set", 'drive.mode="open-loop"']
    assert main([*args, "--out", str(out)]) == 2
    assert "drive.mode" in capsys.readouterr().err
    assert not out.exists()


def test_commissioning_failed_names_the_test():
    exc = CommissioningFailed("ac", "the impedances do not fit")
    assert "'ac'" in str(exc) and "do not fit" in str(exc)


@pytest.mark.slow
def test_a_test_that_does_not_settle_exits_6_and_writes_nothing(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(dc_module, "DWELL_T2", 0.3)  # far too short for the rotor flux
    out = tmp_path / "c"
    assert main(["commission", "sensorless-realistic", "--out", str(out)]) == 6
    err = capsys.readouterr().err
    assert "'dc'" in err and ("settle" in err or "reach" in err)
    assert not (out / "identified.toml").exists()


@pytest.mark.slow
def test_realistic_drive_is_identified_within_the_goals(tmp_path):
    sc = Scenario.read("sensorless-realistic")
    res = commission(sc, tmp_path)
    err = res.relative_error
    assert abs(err["R1_ohm"]) <= 0.03
    assert abs(err["R2_ohm"]) <= 0.05
    assert abs(err["sigma_L1_H"]) <= 0.10
    assert abs(err["L1_H"]) <= 0.05
    assert abs(err["J_kgm2"]) <= 0.10
    assert abs(err["Lm_H"]) <= 0.03
    assert abs(err["u_err_V"]) <= 0.05
    summary = json.loads((tmp_path / "summary.json").read_text())
    for key in ("R1_ohm", "R2_ohm", "sigma_L1_H", "L1_H", "J_kgm2"):
        assert summary["identified"][key] > 0 and summary["true"][key] > 0
    assert set(summary["identified"]["magnetising"]) == {"psi_Wb", "Lm_H"}
    assert set(summary["identified"]["inverter_error"]) == {"i_A", "u_V"}
    data = tomllib.loads((tmp_path / "identified.toml").read_text())
    assert data["estimator"]["R1_ohm"] == pytest.approx(res.identified["R1_ohm"])
    from imdrive.run.simulate import simulate

    run = simulate(Scenario.read(str(tmp_path / "identified.toml")))  # imdrive run's scenario
    assert not run.diverged and not run.lost_control
    assert run.final_values()["speed_rpm"] == pytest.approx(1000.0, abs=5.0)
    for name in ("dc", "no-load", "ac", "acceleration"):
        assert (tmp_path / f"{name}.png").stat().st_size > 0


@pytest.mark.slow
def test_random_plants_are_identified_within_the_goals():
    """The accuracy study at reduced size: three random plants (both library machines)."""
    from imdrive.commission.accuracy import GOALS, accuracy_rows

    rows = accuracy_rows(3, seed=7)
    assert {r["machine"] for r in rows} == {"paper-table-iv", "aalto-2.2kw"}
    for row in rows:
        assert not row["failed"], row["failed"]
        for q, goal in GOALS.items():
            assert abs(row[q]) <= goal / 100.0, (row["plant"], q, row[q])
