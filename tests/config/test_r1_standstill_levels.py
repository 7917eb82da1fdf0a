"""The standstill R1 test's number of current levels where it is unset
(config/r1_standstill.py): two where the controller compensates its inverter's error, one
where it believes the inverter ideal (no residual to separate, no scale to start)."""

import pytest

from imdrive.config.r1_standstill import r1_standstill_levels
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError


@pytest.mark.parametrize(
    ("preset", "sets", "levels"),
    [
        ("injection-robust", [], 1),  # the average inverter, no compensation
        ("injection-robust", ['control.dead_time_compensation="feedforward"'], 2),
        ("sensorless-realistic-uncommissioned", [], 2),  # the assumed dead time
        ("sensorless-realistic", [], 2),  # a commissioned inverter-error table
        ("injection-robust", ["mras.R1_standstill_levels=2"], 2),  # as set
        ("sensorless-realistic", ["mras.R1_standstill_levels=1"], 1),
    ],
)
def test_levels_follow_what_the_controller_knows_of_its_inverter(preset, sets, levels):
    sc = Scenario.read(preset, sets)
    assert r1_standstill_levels(sc) == levels
    if not any("R1_standstill_levels" in s for s in sets):  # `imdrive show --all` says so
        note = f"R1_standstill_levels is unset (its documented default applies: {levels} here)"
        assert note in sc.to_toml()


@pytest.mark.parametrize(
    "bad",
    [
        "mras.R1_standstill_levels=3",
        "mras.R1_standstill_first_level=1",
        "mras.R1_standstill_first_level=0.1",
    ],
)
def test_bad_values_are_refused(bad):
    # three levels do not exist; a first level at the reference leaves no difference (and
    # above it the flux saturates); near zero the dead-time's shape is not a constant
    with pytest.raises(ConfigError, match="mras.R1_standstill"):
        Scenario.read("injection-robust", [bad])
