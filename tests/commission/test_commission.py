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
    assert abs(err["current_gain_b_per_a"]) <= 5e-4  # measured 1.4e-4 (tests/commission/test_dc)
    summary = json.loads((tmp_path / "summary.json").read_text())
    for key in ("R1_ohm", "R2_ohm", "sigma_L1_H", "L1_H", "J_kgm2"):
        assert summary["identified"][key] > 0 and summary["true"][key] > 0
    assert set(summary["identified"]["magnetising"]) == {"psi_Wb", "Lm_H"}
    assert set(summary["identified"]["inverter_error"]) == {"i_A", "u_V"}
    data = tomllib.loads((tmp_path / "identified.toml").read_text())
    assert data["estimator"]["R1_ohm"] == pytest.approx(res.identified["R1_ohm"])
    ratio = res.identified["current_gain_b_per_a"]
    assert data["controller_model"]["current_gain_b_per_a"] == pytest.approx(ratio)
    assert data["controller_model"]["ideal"] is False  # the identified tables, not the plant's
    from imdrive.run.simulate import simulate

    run = simulate(Scenario.read(str(tmp_path / "identified.toml")))  # imdrive run's scenario
    assert not run.diverged and not run.lost_control
    assert run.final_values()["speed_rpm"] == pytest.approx(1000.0, abs=5.0)
    for name in ("dc", "no-load", "ac", "acceleration"):
        assert (tmp_path / f"{name}.png").stat().st_size > 0


@pytest.mark.slow
def test_random_plants_are_identified_within_the_goals():
    """The accuracy study at reduced size: one random plant (another seed than the docs')
    of three library machines, the 50 hp one included."""
    from imdrive.commission.accuracy import GOALS, accuracy_rows

    machines = ("paper-table-iv", "aalto-2.2kw", "krause-50hp")
    rows = accuracy_rows(1, seed=7, only=machines)
    assert [r["machine"] for r in rows] == list(machines)
    for row in rows:
        assert not row["failed"], row["failed"]
        for q, goal in GOALS.items():
            assert abs(row[q]) <= goal / 100.0, (row["machine"], q, row[q])


@pytest.mark.slow
def test_a_level_that_has_not_settled_is_measured_longer():
    """Krause 50 hp's plant 1 of the docs' accuracy table: its 0.8 x rated flux level moved L1
    3.6 % between the two halves of a 10 T2 dwell and the commissioning stopped (exit 6); the
    test now runs again with twice the dwell and identifies within the goals."""
    import imdrive.commission.noload as nl
    from imdrive.commission.accuracy import GOALS, accuracy_row

    row = accuracy_row("krause-50hp", 1)
    assert not row["failed"], row["failed"]
    for q, goal in GOALS.items():
        assert abs(row[q]) <= goal / 100.0, (q, row[q])
    doublings, nl.DWELL_DOUBLINGS = nl.DWELL_DOUBLINGS, 0
    try:
        assert "did not settle in" in accuracy_row("krause-50hp", 1)["failed"]
    finally:
        nl.DWELL_DOUBLINGS = doublings


# --- what the drive knows: the nameplate, never the plant ---------------------------------


def test_nameplate_reads_no_plant_parameter():
    """The test currents, speed and torque are the nameplate's: two plants with the same
    nameplate and circuits 30 % apart give the same figures (the rated current was the
    circuit's when the plate lacked it)."""
    from imdrive.commission.base import nameplate

    sets = ['machine.preset="krause-50hp"']
    a = nameplate(Scenario.read("sensorless-realistic", sets))
    other = ["machine.R1_ohm=0.1", "machine.R2_ohm=0.07", "machine.M_H=0.03"]
    b = nameplate(Scenario.read("sensorless-realistic", [*sets, *other]))
    assert (a.I_rated_A, a.speed_rpm, a.torque_Nm) == (b.I_rated_A, b.speed_rpm, b.torque_Nm)
    assert a.sources["current"].startswith("P / (sqrt 3 V eta cos phi)")
    # P / (sqrt 3 V 0.8), peak
    assert a.I_rated_A == pytest.approx(2**0.5 * 37285.0 / (3**0.5 * 460.0 * 0.8))
    assert a.speed_rpm == 1705.0


def test_nameplate_current_and_missing_speed():
    from imdrive.commission.base import nameplate

    given = nameplate(Scenario.read("sensorless-realistic", ["machine.rated_current_rms_A=9"]))
    assert given.I_rated_A == pytest.approx(9.0 * 2**0.5)
    assert given.sources["current"] == "nameplate"
    # Table IV's plate has no speed: the synchronous speed, not the circuit's
    assert given.speed_rpm == 1800.0 and given.sources["speed"].startswith("synchronous")
    eta_pf = ["machine.rated_efficiency=0.9", "machine.rated_power_factor=0.8"]
    npl = nameplate(Scenario.read("sensorless-realistic", eta_pf))
    assert npl.I_rated_A == pytest.approx(2**0.5 * 2238.0 / (3**0.5 * 220.0 * 0.72))


# --- the rotor time constant's step test ----------------------------------------------------


def test_exponential_fit_finds_the_time_constant_and_refuses_a_truncated_one():
    import numpy as np

    from imdrive.commission.rotor_time import _fit_exponential

    t = np.linspace(0.0, 2.0, 400)
    rng = np.random.default_rng(0)
    v = 10.0 + 3.0 * np.exp(-t / 0.2) + 0.01 * rng.standard_normal(t.size)
    T, fit = _fit_exponential(t, v)
    assert T == pytest.approx(0.2, rel=0.02)
    assert np.max(np.abs(fit - v)) < 0.05
    # a time constant far beyond the window is not trusted
    T_long, _ = _fit_exponential(t, 10.0 + 3.0 * np.exp(-t / 500.0))
    assert T_long is None


# --- starting from any preset --------------------------------------------------------------


def test_r2_tracking_preset_test_scenarios_switch_off_what_the_tests_cannot_run_with():
    from imdrive.commission.base import switched_off, test_scenario

    sc = Scenario.read("injection-robust")
    lines = switched_off(sc)
    for key in (
        "compensator.enabled",
        "injection",
        "control.field_weakening",
        "mras.R1_standstill",
        "mras.R1_rate_pu",
    ):
        assert any(line.startswith(key) for line in lines), (key, lines)
    # it was exit 2 (injection.headroom_voltage needs field weakening); frequency_pu of the
    # user's injection no longer overrides the AC test's frequency
    scen = test_scenario(sc, "ac", 1.0, injection={"amplitude_A": 1.36, "frequency_Hz": 3.0})
    assert scen.injection.frequency_pu is None and scen.injection.frequency_Hz == 3.0
    assert scen.injection.amplitude_A == 1.36 and scen.injection.amplitude_pu is None
    assert not scen.compensator.enabled and not scen.mras.R1_standstill
    assert switched_off(Scenario.read("sensorless")) == []


@pytest.mark.slow
def test_injection_robust_commissions_and_says_what_it_switched_off(tmp_path, capsys):
    out = tmp_path / "c"
    assert main(["commission", "injection-robust", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    switched = [line for line in text.splitlines() if line.startswith("switched off")]
    assert len(switched) == 5, switched  # one line per setting
    data = tomllib.loads((out / "identified.toml").read_text())
    assert data["compensator"]["enabled"] is True  # the scenario keeps its R2 tracking


# --- every library machine ------------------------------------------------------------------


@pytest.mark.slow
def test_krause_50hp_is_commissioned():
    """It stopped in the DC test in 7 of 7 tries (each level lasted 12/w_slip, 3.9 T2)."""
    from imdrive.commission.identify import identify

    sc = Scenario.read("sensorless-realistic", ['machine.preset="krause-50hp"'])
    res = identify(sc)
    T2_unsat = (sc.machine.M_H / sc.plant.saturation.rated_ratio + sc.machine.Ll2_H) / (
        sc.machine.R2_ohm
    )
    assert res.identified["T2_step_s"] == pytest.approx(T2_unsat, rel=0.03)
    for q, goal in (("R1_ohm", 0.03), ("R2_ohm", 0.05), ("sigma_L1_H", 0.05), ("J_kgm2", 0.1)):
        assert abs(res.relative_error[q]) <= goal, (q, res.relative_error[q])


@pytest.mark.slow
def test_sigma_L1_of_the_500hp_machine_is_unbiased():
    """-7.8 % before (ADC quantisation, and frequencies where the leakage is 1-7 % of |Z|);
    without the dither -3 %."""
    from imdrive.commission.identify import identify

    sc = Scenario.read("sensorless-realistic", ['machine.preset="krause-500hp"'])
    err = identify(sc).relative_error
    assert abs(err["sigma_L1_H"]) <= 0.015, err["sigma_L1_H"]
    assert abs(err["R2_ohm"]) <= 0.02, err["R2_ohm"]


# --- identified.toml ---------------------------------------------------------------------


@pytest.mark.slow
def test_identified_toml_runs_after_the_folder_is_moved(tmp_path, monkeypatch):
    import shutil

    from imdrive.run.simulate import simulate

    motor = tmp_path / "motors" / "m.toml"
    motor.parent.mkdir()
    from imdrive.config.machine import preset_table

    table = preset_table("krause-3hp")
    motor.write_text(
        "".join(f"{k} = {v!r}\n" for k, v in table.items() if isinstance(v, int | float))
    )
    sc = Scenario.read("sensorless-realistic", [f'machine.file="{motor.as_posix()}"'])
    commission(sc, tmp_path / "a")
    text = (tmp_path / "a" / "identified.toml").read_text()
    data = tomllib.loads(text)
    assert "preset" not in data["machine"] and "file" not in data["machine"]
    assert "uncommissioned" not in data["description"]
    assert "imdrive commission" in data["description"]
    shutil.move(tmp_path / "a", tmp_path / "elsewhere" / "b")
    shutil.rmtree(motor.parent)
    monkeypatch.chdir(tmp_path / "elsewhere")
    run = simulate(Scenario.read("b/identified.toml"))
    assert not run.diverged and not run.lost_control
    # sensorless-realistic's speed reference is per-unit (0.5811 of the rated speed, 1000 rpm
    # on Table IV): on Krause's 3 hp motor about 993.7 rpm, which the commissioned drive
    # reaches (measured 993.95 rpm; it was 1000 rpm on every machine while the preset stated
    # rpm, and the 6 rpm difference failed the old bound)
    from imdrive.config.rated import rated_point

    ref = 0.5811 * rated_point(run.scenario.machine).speed_rpm
    assert run.final_values()["speed_ref_rpm"] == pytest.approx(ref, rel=1e-9)
    assert run.final_values()["speed_rpm"] == pytest.approx(ref, abs=5.0)
