"""The ``load_pu_available`` sweep axis: the load in per-unit of the torque the machine carries
at the run's speed on rated voltage (rated torque up to rated speed, then constant power,
bounded by the breakdown torque), checked against the equivalent circuit on two machines."""

from __future__ import annotations

import pytest

from imdrive.analysis.circuit import breakdown
from imdrive.config.profile_units import stated_load_Nm, stated_speed_ref_rpm
from imdrive.config.rated import rated_point
from imdrive.sweep.spec import parse_sweep


def _sweep(machine: str, speeds, loads) -> object:
    return parse_sweep(
        f'base = "sensorless"\n[set]\n"machine.preset" = "{machine}"\n'
        f"[axes]\nspeed_pu = {list(speeds)}\nload_pu_available = {list(loads)}\n"
    )


@pytest.mark.parametrize("machine", ["paper-table-iv", "krause-50hp"])
def test_available_torque_is_rated_then_constant_power_and_carried_by_the_circuit(machine):
    speeds = (-0.5, 1.0, 1.5, 2.0, 3.0)
    sw = _sweep(machine, speeds, (1.0,))
    m = sw.scenario(0).machine
    rp = rated_point(m)
    for k, x in enumerate(speeds):
        sc = sw.scenario(k)
        assert stated_speed_ref_rpm(sc).points[-1][1] == pytest.approx(x * rp.speed_rpm)
        T = stated_load_Nm(sc).points[-1][1]
        if abs(x) <= 1.0:
            assert T == pytest.approx(rp.torque_Nm, rel=1e-12)
            continue
        # never more than the rated power ...
        assert T * abs(x) <= rp.torque_Nm * (1 + 1e-12)
        # ... and below the breakdown torque of the circuit at that frequency, rated voltage
        f = abs(x) * m.rated_frequency_Hz
        _, T_bd = breakdown(m, m.rated_voltage_V, f)
        assert T <= T_bd * (1 + 1e-6)
        # one of the two bounds is the one taken
        assert T == pytest.approx(min(rp.torque_Nm / abs(x), T_bd), rel=0.05)


def test_available_load_scales_and_keeps_the_sign():
    sw = _sweep("paper-table-iv", (2.0,), (-1.0, -0.5, 0.5))
    T = [stated_load_Nm(sw.scenario(k)).points[-1][1] for k in range(3)]
    assert T[0] == pytest.approx(-2 * T[2]) and T[1] == pytest.approx(-T[2])
