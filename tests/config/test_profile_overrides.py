"""One element of a profile can be overridden (``--set 'control.speed_ref_rpm.changes[0].to=300'``)
without rewriting the whole profile; a missing element is a one-line ConfigError."""

from __future__ import annotations

import re

import pytest

import imdrive as im
from imdrive.cli import main
from imdrive.config.overrides import parse_override
from imdrive.errors import ConfigError


def test_parse_override_reads_indices():
    parts, value = parse_override("control.speed_ref_rpm.changes[0].to=300")
    assert parts == ("control", "speed_ref_rpm", "changes", 0, "to") and value == 300


@pytest.mark.parametrize("how", ["read", "with_overrides"])
def test_one_change_of_a_profile(how):
    ov = ["control.speed_ref_rpm.changes[0].to=300", "load.torque_Nm.changes[0].at=1.8"]
    base = im.Scenario.read("paper-fig5")  # its profiles in rpm and N m
    sc = im.Scenario.read("paper-fig5", ov) if how == "read" else base.with_overrides(ov)
    # the rest of the profiles as they were: the same start, ramp time and load
    assert sc.control.speed_ref_rpm.points == ((0.0, 0.0), (0.5, 0.0), (1.5, 300.0))
    assert sc.load.torque_Nm.points == ((0.0, 0.0), (1.8, 0.0), (1.8, 12.0))
    assert sc.control == base.control.__class__(
        **{**base.control.__dict__, "speed_ref_rpm": sc.control.speed_ref_rpm}
    )


def test_one_change_of_a_per_unit_profile():
    ov = ["control.speed_ref_pu.changes[0].to=0.2", "load.torque_pu.changes[0].over=0.5"]
    sc = im.Scenario.read("sensorless", ov)
    assert sc.control.speed_ref_pu.points == ((0.0, 0.0), (0.5, 0.0), (1.5, 0.2))
    assert sc.load.torque_pu.points == ((0.0, 0.0), (2.0, 0.0), (2.5, 0.9663))
    # an element of the rpm profile the preset no longer states: one line naming its twin
    with pytest.raises(ConfigError, match=re.escape("set control.speed_ref_pu.changes[0].to")):
        im.Scenario.read("sensorless", ["control.speed_ref_rpm.changes[0].to=300"])


def test_a_step_becomes_a_ramp():
    sc = im.Scenario.read("paper-fig5", ["load.torque_Nm.changes[0].over=0.5"])
    assert sc.load.torque_Nm.points == ((0.0, 0.0), (2.0, 0.0), (2.5, 12.0))


@pytest.mark.parametrize(
    "spec, words",
    [
        ("control.speed_ref_rpm.changes[3].to=1", "no such element (the list has 1)"),
        ("control.speed_ref_rpm.nope=1", "no such setting"),
        ("control.speed_kp[0]=1", "no such setting"),
        ("control.speed_ref_rpm.changes[x].to=1", "an index is written name[0]"),
    ],
)
def test_bad_element_is_one_config_error(spec, words):
    with pytest.raises(ConfigError, match=re.escape(words)):
        im.Scenario.read("paper-fig5", [spec])


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_cli_set_one_element(tmp_path, capsys):
    out = tmp_path / "r"
    code = main(["show", "sensorless", "--all"])
    assert code == 0
    capsys.readouterr()
    code = main(
        ["run", "sensorless", "--set", "control.speed_ref_pu.changes[0].to=0.1743",
         "--set", "simulation.t_end_s=2", "--out", str(out), "-q"]
    )  # fmt: skip
    assert code == 0
    import json

    summary = json.loads((out / "summary.json").read_text())
    assert summary["final"]["speed_rpm"] == pytest.approx(300.0, abs=2.0)
    assert main(["run", "sensorless", "--set", "control.speed_ref_pu.changes[5].to=1"]) == 2
    assert "changes[5]: no such element" in capsys.readouterr().err


def test_peak_is_the_largest_magnitude_of_a_reversing_profile():
    from imdrive.config.profiles import parse_profile

    p = parse_profile(
        "control.speed_ref_rpm",
        {"initial": 0, "changes": [{"at": 0.5, "to": 1000, "over": 1}, {"at": 3, "to": -1500}]},
    )
    assert p.peak == 1500.0
    assert parse_profile("load.torque_Nm", -12.0).peak == 12.0
