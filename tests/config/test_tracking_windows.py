"""``simulation.tracking_windows``: a run's length in R2 tracking's decision windows."""

from __future__ import annotations

import pytest

from imdrive.config.perunit import resolve
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError


def _window_s(sc) -> float:
    return resolve(sc).n_comp * sc.simulation.Ts_s


@pytest.mark.parametrize("machine", ["paper-table-iv", "aalto-2.2kw", "krause-2250hp"])
def test_the_run_ends_that_many_windows_after_tracking_starts(machine):
    sc = Scenario.read("injection-robust", [f'machine.preset="{machine}"'])
    assert sc.simulation.tracking_windows == 20
    end = sc.compensator.t_on_s + 20 * _window_s(sc)
    assert sc.simulation.t_end_s == pytest.approx(end, rel=1e-12)
    if machine == "paper-table-iv":
        assert sc.simulation.t_end_s == 14.0  # the preset's length until round 4


def test_a_stated_length_replaces_it_and_the_windows_replace_a_length():
    sc = Scenario.read("injection-robust", ["simulation.t_end_s=3"])
    assert sc.simulation.t_end_s == 3.0 and sc.simulation.tracking_windows is None
    sc = Scenario.read("sensorless", ["simulation.tracking_windows=4"])
    # no compensator: its decision window still counts (a drive that does not track runs as
    # long as one that does)
    assert sc.simulation.t_end_s == pytest.approx(sc.compensator.t_on_s + 4 * _window_s(sc))


def test_written_out_it_is_derived_again():
    sc = Scenario.read("injection-robust")
    assert "t_end_s" not in sc.to_dict()["simulation"]
    other = sc.with_overrides(['machine.preset="krause-500hp"'])
    assert other.simulation.t_end_s == pytest.approx(
        other.compensator.t_on_s + 20 * _window_s(other), rel=1e-12
    )
    again = Scenario.from_toml(other.to_toml())
    assert again.simulation.t_end_s == other.simulation.t_end_s


def test_both_in_one_file_are_refused(tmp_path):
    from imdrive.config.presets import scenario_text

    text = scenario_text("injection-robust").replace(
        "tracking_windows = 20", "tracking_windows = 20\nt_end_s = 9.0"
    )
    path = tmp_path / "both.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match="simulation.t_end_s or simulation.tracking_windows"):
        Scenario.read(str(path))


@pytest.mark.parametrize("value", ["0", "-1", "1.5", "2000000"])
def test_bad_values_name_the_field(value):
    with pytest.raises(ConfigError, match="simulation.tracking_windows"):
        Scenario.read("injection-robust", [f"simulation.tracking_windows={value}"])
