"""A sweep point's convenience axes are applied section by section and validated once
(sweep/model.py ``_Draft``): the scenario is the one that applying the axes one at a time,
each step a whole validated scenario, gives."""

from __future__ import annotations

from dataclasses import replace

import pytest

from imdrive.config.rated import rated_point
from imdrive.sweep import parse_sweep
from imdrive.sweep.model import _overridden, _with_final, available_torque_Nm

SWEEP = """
name = "draft"
base = "sensorless"
samples = 6
seed = 3

[set]
machine.preset = "krause-50hp"
control.speed_ref_rpm = { initial = 0, changes = [{ at = 0.1, to = 1000, over = 0.3 }] }
load.torque_Nm = { initial = 0, changes = [{ at = 0.5, to = 12 }] }

[axes]
R2_ratio = { min = 0.6, max = 1.4 }
speed_pu = { min = 0.1, max = 1.8 }
load_pu_available = { min = -1, max = 1 }
"""


def _one_at_a_time(sw, point):
    sc = _overridden(sw, point)
    sc = replace(sc, estimator=replace(sc.estimator, R2_ohm=None, R2_ratio=point["R2_ratio"]))
    rpm = point["speed_pu"] * rated_point(sc.machine).speed_rpm
    speed = _with_final(sc.control.speed_ref_rpm, rpm)
    sc = replace(sc, control=replace(sc.control, speed_ref_rpm=speed))
    torque = point["load_pu_available"] * available_torque_Nm(sc)
    return replace(sc, load=replace(sc.load, torque_Nm=_with_final(sc.load.torque_Nm, torque)))


@pytest.mark.parametrize("i", range(6))
def test_one_validation_gives_the_scenario_of_one_per_axis(i):
    sw = parse_sweep(SWEEP)
    point = dict(zip([a.name for a in sw.axes], sw.run_values(i), strict=True))
    got = sw.scenario(i)
    assert got == _one_at_a_time(sw, point)
    assert got.estimator.R2_ratio == point["R2_ratio"]
    assert got.control.speed_ref_rpm.points[-1][1] == pytest.approx(
        point["speed_pu"] * rated_point(got.machine).speed_rpm
    )
