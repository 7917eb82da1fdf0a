"""``controller_model.ideal``: the tables an ideal commissioning identifies on the scenario's
own plant, derived when the scenario is read (config/commissioning_ideal.py)."""

from __future__ import annotations

import math
import warnings

import pytest

from imdrive.config.commissioning_ideal import ideal_commissioning
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning

REALISTIC = (
    "sensorless-realistic",
    "paper-fig5-realistic",
    "paper-fig6-realistic",
    "injection-fig5-realistic",
    "injection-fig6-realistic",
)


@pytest.mark.parametrize("preset", REALISTIC)
def test_the_realistic_presets_keep_the_tables_they_stated(preset):
    """Until 2026-11-29 each preset stated Table IV's tables, printed by the same function:
    ``ideal = true`` gives them to the bit (its runs are unchanged)."""
    cm = Scenario.read(preset).controller_model
    assert cm.ideal
    assert cm.inverter_error_i_A == (0.0, 0.2, 33.224)
    assert cm.inverter_error_u_V == (0.0, 7.22254, 7.22254)
    assert len(cm.magnetising_psi_Wb) == 25
    assert cm.magnetising_Lm_H[16] == 0.0693  # the rated flux's secant: M of Table IV


@pytest.mark.parametrize("machine", ["aalto-2.2kw", "krause-500hp", "geyer-3.3kv"])
def test_the_tables_follow_a_change_of_machine_without_a_warning(machine):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sc = Scenario.read("sensorless-realistic", [f'machine.preset="{machine}"'])
    assert not [w for w in caught if "controller_model" in str(w.message)]
    cm, inv = sc.controller_model, sc.inverter
    u = inv.dead_time_s * inv.switching_frequency_Hz * inv.Vdc_V + inv.device_drop_V
    assert cm.inverter_error_u_V[1] == pytest.approx(u, rel=1e-5)
    # the curve's node at the rated flux is the plant's secant there, the machine's M
    k = [round(p / sc.machine.rated_flux_Wb, 4) for p in cm.magnetising_psi_Wb].index(1.0)
    assert cm.magnetising_Lm_H[k] == pytest.approx(sc.machine.M_H, rel=1e-5)
    assert tuple(ideal_commissioning(sc)["magnetising_Lm_H"]) == cm.magnetising_Lm_H


def test_the_tables_follow_the_inverter_too():
    a = Scenario.read("sensorless-realistic", ["inverter.dead_time_s=4e-6"]).controller_model
    b = Scenario.read("sensorless-realistic").controller_model
    # the dead time's share doubles (6 significant digits each)
    assert a.inverter_error_u_V[1] - 1.0 == pytest.approx(
        2 * (b.inverter_error_u_V[1] - 1.0), abs=1e-4
    )


def test_given_tables_that_differ_are_replaced_with_a_warning():
    with pytest.warns(ConfigWarning, match="controller_model.ideal"):
        sc = Scenario.read(
            "sensorless-realistic",
            [
                "controller_model.inverter_error_i_A=[0, 1]",
                "controller_model.inverter_error_u_V=[0, 3]",
            ],
        )
    assert sc.controller_model.inverter_error_u_V[1] == 7.22254
    # off, the preset states no tables: the constant model of an uncommissioned controller
    off = Scenario.read("sensorless-realistic", ["controller_model.ideal=false"])
    assert off.controller_model.inverter_error_u_V == () and not off.controller_model.ideal


def test_without_saturation_or_inverter_loss_there_is_nothing_to_identify():
    sc = Scenario.read("sensorless", ["controller_model.ideal=true"])
    assert sc.controller_model.magnetising_psi_Wb == ()
    assert sc.controller_model.inverter_error_i_A == ()
    assert not math.isnan(sc.machine.M_H)


@pytest.mark.slow
@pytest.mark.parametrize("machine", ["aalto-2.2kw", "krause-2250hp"])
def test_the_realistic_drive_runs_on_another_machine_with_only_the_machine_changed(machine):
    """With Table IV's tables kept, ``sensorless-realistic`` lost control on the Aalto
    2.2 kW machine (0.65 s), Krause 500 and 2250 hp and the 3.3 kV machine, and ended 13.8 rpm
    off on Krause 50 hp; with its own ideal commissioning every library machine ends "ok"."""
    from imdrive.run.simulate import simulate

    res = simulate(Scenario.read("sensorless-realistic", [f'machine.preset="{machine}"']))
    assert res.verdict["verdict"] == "ok", res.verdict["verdict_text"]


def test_the_sensors_relative_gain_is_the_plants_and_follows_it():
    """``controller_model.current_gain_b_per_a`` unset: the plant's ``g_b/g_a`` with
    ``ideal = true``, derived at use (a change of the sensors' gains is followed), 1 without;
    a value given is kept, 1 included (the drive uncalibrated)."""
    from imdrive.config.commissioning_ideal import current_gain_b_per_a

    sc = Scenario.read("sensorless-realistic")
    assert current_gain_b_per_a(sc) == pytest.approx(0.9975 / 1.0025, rel=1e-12)
    moved = sc.with_overrides({"sensor.gain_b": 1.01})
    assert current_gain_b_per_a(moved) == pytest.approx(1.01 / 1.0025, rel=1e-12)
    assert current_gain_b_per_a(sc.with_overrides({"controller_model.ideal": False})) == 1.0
    kept = sc.with_overrides({"controller_model.current_gain_b_per_a": 1.0})
    assert current_gain_b_per_a(kept) == 1.0
    assert current_gain_b_per_a(Scenario.read("sensorless")) == 1.0  # ideal sensors
