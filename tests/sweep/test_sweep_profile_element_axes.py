"""A sweep axis (and a ``[set]`` key) may reach into one element of a profile, as ``--set``
does: ``"control.speed_ref_rpm.changes[0].to" = [...]``."""

from __future__ import annotations

import pytest

from imdrive import Scenario
from imdrive.errors import ConfigError
from imdrive.sweep.spec import parse_sweep

SWEEP = """
base = "paper-fig5"  # its profiles in rpm and N m
[set]
"simulation.t_end_s" = 3.0
"load.torque_Nm.changes[0].at" = 2.5
[axes]
"control.speed_ref_rpm.changes[0].to" = [300.0, 600.0]
R2_ratio = [1.1]
"""


def test_axis_over_one_profile_element_builds_what_set_builds():
    sw = parse_sweep(SWEEP)
    assert sw.n_runs == 2
    for k, rpm in enumerate((300.0, 600.0)):
        got = sw.scenario(k)
        want = Scenario.read(
            "paper-fig5",
            [
                "simulation.t_end_s=3.0",
                "load.torque_Nm.changes[0].at=2.5",
                f"control.speed_ref_rpm.changes[0].to={rpm}",
            ],
        )
        assert got.control.speed_ref_rpm == want.control.speed_ref_rpm
        assert got.control.speed_ref_rpm.points[-1][1] == rpm
        assert got.load.torque_Nm == want.load.torque_Nm
        assert got.load.torque_Nm.points[1][0] == 2.5
        assert got.estimator.R2_ratio == 1.1


@pytest.mark.parametrize(
    ("axes", "field"),
    [
        ('"control.speed_ref_rpm.changes[5].to" = [1.0]', "changes[5]"),
        ('"control.speed_ref_rpm.changes[0].when" = [1.0]', "axes.control.speed_ref_rpm"),
        ('"control.speed_bandwidth_Hz[0]" = [1.0]', "axes.control.speed_bandwidth_Hz[0]"),
    ],
)
def test_bad_profile_element_axis_names_the_field(axes, field):
    with pytest.raises(ConfigError) as exc:
        parse_sweep(f'base = "sensorless"\n[axes]\n{axes}\n')
    assert field in str(exc.value)


def test_two_axes_on_the_same_element_are_refused():
    text = SWEEP.replace("R2_ratio = [1.1]", '"control.speed_ref_rpm" = [{initial = 0.0}]')
    with pytest.raises(ConfigError, match="two axes may not set the same key"):
        parse_sweep(text)
