"""Bad input is refused early, in one line that names the field and the rule."""

import tomllib

import pytest

import imdrive as im
from imdrive.cli import main
from imdrive.config.machine import machine_preset
from imdrive.errors import ConfigError


def test_show_a_machine_preset_prints_its_parameters(capsys):
    assert main(["show", "paper-table-iv"]) == 0
    out = capsys.readouterr().out
    data = tomllib.loads(out)
    m = machine_preset("paper-table-iv")
    assert data["machine"]["preset"] == "paper-table-iv"
    assert data["machine"]["R2_ohm"] == m.R2_ohm and data["machine"]["M_H"] == m.M_H
    # and the table drops into a scenario as it is
    sc = im.Scenario.from_dict({"name": "mine", "drive": {"mode": "vector"}, **data})
    assert sc.machine == m


def test_a_string_in_place_of_the_override_list_is_refused():
    with pytest.raises(ConfigError, match=r"overrides: must be a list.*\['simulation.t_end_s=1'\]"):
        im.Scenario.read("sensorless", "simulation.t_end_s=1")
    with pytest.raises(ConfigError, match="overrides: must be a list"):
        im.Scenario.read("sensorless").with_overrides("simulation.t_end_s=1")


@pytest.mark.parametrize("bad", [{"name": "x"}, "sensorless", None])
def test_simulate_refuses_anything_but_a_scenario_at_once(bad):
    with pytest.raises(ConfigError, match="simulate\\(\\) needs a Scenario"):
        im.simulate(bad)


def test_simulate_batch_names_the_item_that_is_not_a_scenario():
    good = im.Scenario.read("sensorless", ["simulation.t_end_s=0.2"])
    with pytest.raises(ConfigError, match=r"scenarios\[1\]: must be a Scenario, got dict"):
        im.simulate_batch([good, {"name": "x"}])
    with pytest.raises(ConfigError, match="must be an iterable of Scenario"):
        im.simulate_batch(good)


def test_default_log_every_follows_a_new_Ts_in_with_overrides():
    sc = im.Scenario.from_dict({"name": "x", "drive": {"mode": "vector"}})
    assert sc.simulation.log_every == 10  # 1 kHz at 100 us
    assert sc.with_overrides(["simulation.Ts_s=1e-3"]).simulation.log_every == 1
    assert sc.with_overrides(["simulation.Ts_s=5e-5"]).simulation.log_every == 20
    # a value the user set stays
    mine = im.Scenario.from_dict({"name": "x", "simulation": {"log_every": 3}})
    assert mine.with_overrides(["simulation.Ts_s=1e-3"]).simulation.log_every == 3
