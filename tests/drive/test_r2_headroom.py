"""R2 near and above base speed: the estimation headroom (kernels/compensator.py,
headroom_weakening_input) and its cost in torque per ampere (analysis/headroom.py).

Points chosen here, on two machines of the library: Table IV (base speed about 1720 rpm) and
the 2.2 kW Aalto machine (about 1440 rpm), each at rated load just below synchronous speed
(the voltage limit) and at light load at about 1.4 times base speed (field weakening).
"""

from __future__ import annotations

import numpy as np
import pytest
from data.headroom import HEADROOM, NO_HEADROOM

from imdrive.analysis.headroom import oriented_point, torque_per_ampere_at_flux
from imdrive.config.machine import rated_point
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.run.simulate import simulate


def _run(machine, speed_rpm, torque_Nm, extra, ramp_s=1.0, t_end=14.0):
    sc = Scenario.read(
        "injection-robust",
        [
            f'machine.preset="{machine}"',
            f"control.speed_ref_rpm={{initial=0,changes=[{{at=0.5,to={speed_rpm},over={ramp_s}}}]}}",
            f"load.torque_Nm={{initial=0,changes=[{{at={1.0 + ramp_s},to={torque_Nm}}}]}}",
            f"simulation.t_end_s={t_end}",
            *(() if isinstance(extra, dict) else extra),
        ],
    )
    if isinstance(extra, dict):
        sc = sc.with_overrides(extra)
    return sc, simulate(sc)


def _tail(res, name, seconds=1.0):
    t = res.signals["time_s"]
    return res.signals[name][t >= t[-1] - seconds]


@pytest.mark.slow
@pytest.mark.parametrize(
    "machine, speed_rpm, load_pu, ramp_s",
    [
        ("paper-table-iv", 1600, 1.0, 1.0),  # 0.93 of synchronous speed, at the voltage limit
        ("aalto-2.2kw", 1450, 1.0, 1.0),  # 0.97 of synchronous speed
        ("paper-table-iv", 2400, 0.32, 3.0),  # 1.4 x base speed, field weakening
        ("aalto-2.2kw", 2200, 0.34, 3.0),  # 1.5 x base speed
    ],
)
def test_R2_converges_near_and_above_base_speed_with_the_headroom(
    machine, speed_rpm, load_pu, ramp_s
):
    sc, res = _run(machine, speed_rpm, 0.0, ("load.torque_Nm=0",), ramp_s, t_end=0.1)
    torque = round(load_pu * rated_point(sc.machine).torque_Nm, 2)
    sc, res = _run(machine, speed_rpm, torque, HEADROOM, ramp_s, t_end=16.0)
    R2 = sc.machine.R2_ohm
    assert not res.diverged and not res.lost_control
    R2_hat = _tail(res, "R2_hat_ohm")
    assert np.max(np.abs(R2_hat / R2 - 1.0)) < 0.02
    speed_err = _tail(res, "speed_rpm") - speed_rpm
    assert abs(np.mean(speed_err)) < 1.0
    # estimated, not held: no decision of the last 3 s frozen by the injection's back-off
    flags = _tail(res, "comp_frozen_flags", 3.0).astype(int)
    assert not np.any(flags & 32)


@pytest.mark.slow
def test_without_the_headroom_R2_hat_is_held_at_the_voltage_limit():
    # the reference the headroom is measured against: the same point, the injection backs off
    # (the thermal model off: the plant does not heat, R2_hat stays exactly where it started)
    sc, res = _run("paper-table-iv", 1600, 12.0, NO_HEADROOM | {"compensator.thermal_model": False})
    flags = _tail(res, "comp_frozen_flags", 3.0).astype(int)
    assert np.all(flags & 32)
    assert _tail(res, "R2_hat_ohm")[-1] == pytest.approx(1.2 * sc.machine.R2_ohm)


def test_oriented_point_matches_the_circuit_relations():
    m = Scenario.read("injection-robust").machine
    p = oriented_point(m, 1600.0, 12.0, 0.43)
    assert 1.5 * m.pole_pairs * m.M_H / (m.Ll2_H + m.M_H) * p.flux_Wb * p.i_q_A == pytest.approx(
        12.0
    )
    assert p.i_d_A == pytest.approx(0.43 / m.M_H)
    # lowering the flux at light load (i_d > i_q) gains torque per ampere, at rated load costs
    assert torque_per_ampere_at_flux(m, 1600.0, 2.0, 0.43, 0.9) > 1.0
    assert torque_per_ampere_at_flux(m, 1600.0, 12.0, 0.43, 0.9) < 1.0
    with pytest.raises(ConfigError, match="factor"):
        torque_per_ampere_at_flux(m, 1600.0, 12.0, 0.43, 1.2)


@pytest.mark.slow
def test_headroom_cost_in_torque_per_ampere_matches_the_steady_state_circuit():
    # the drive's own measurement of the cost against the circuit's prediction at the flux it
    # settled at: at rated load, 1600 rpm on Table IV
    out = {}
    for key, extra in (("with", HEADROOM), ("without", NO_HEADROOM)):
        sc, res = _run("paper-table-iv", 1600, 12.0, extra)
        i = np.hypot(_tail(res, "i_d_A"), _tail(res, "i_q_A"))
        out[key] = (
            np.mean(_tail(res, "flux_Wb")),
            np.mean(np.abs(_tail(res, "torque_Nm")) / i),
        )
    m = sc.machine
    factor = out["with"][0] / out["without"][0]
    assert 0.85 < factor < 0.97  # a few percent of flux
    measured = out["with"][1] / out["without"][1]
    predicted = torque_per_ampere_at_flux(m, 1600.0, 12.0, out["without"][0], factor)
    assert measured == pytest.approx(predicted, abs=0.01)
    assert predicted < 0.99  # it costs at rated load


def test_headroom_voltage_needs_field_weakening():
    sc = Scenario.read(
        "injection-robust", ["injection.headroom_voltage=0.8", "control.field_weakening=false"]
    )
    from imdrive.run.build import build_arrays

    with pytest.raises(ConfigError, match="injection.headroom_voltage"):
        build_arrays(sc)


@pytest.mark.slow
def test_headroom_yields_when_the_speed_is_not_held():
    # rated motoring torque at 1.4 x base speed is beyond the machine's power (3.1 of 2.2 kW):
    # with the flux lowered for the injection regardless, the load ran the drive away (to the
    # divergence bound, measured); the headroom now yields to the field weakening's own rule
    # while the speed is not held, and the drive stays in control (R2_hat held, flagged)
    sc = Scenario.read(
        "injection-robust",
        [
            "control.speed_ref_rpm={initial=0,changes=[{at=0.5,to=2400,over=2.24}]}",
            "load.torque_Nm={initial=0,changes=[{at=3.24,to=12.418}]}",
            "estimator.R2_ratio=0.8",
            "simulation.t_end_s=18",
        ],
    )
    res = simulate(sc)
    assert not res.diverged and not res.lost_control
    assert _tail(res, "comp_live_flag", 3.0).max() == 0.0  # not estimated: says so


@pytest.mark.slow
@pytest.mark.parametrize("R2_ratio", [1.0, 0.7])
def test_no_gate_limit_cycle_at_base_speed_with_rated_load(R2_ratio):
    # the envelope's cell at the rated speed with the rated load: each trip of the speed gate
    # used to hand the flux to the field weakening's fast rule, whose flux step tripped the
    # gate again (+-2.5 rpm, R2_hat held 66 % of the time and 8 % off, measured); the headroom
    # now only stops lowering the flux unless the torque current is at its limit
    from imdrive.sweep import load_sweep

    sw = load_sweep("envelope-full")
    point = dict(
        speed_pu=1.0,
        load_pu_available=1.0,
        R2_ratio=R2_ratio,
        R1_ratio=1.1,
        thermal="constant",
        inverter="ideal",
    )
    sc = sw.scenario_for(tuple(point[a.name] for a in sw.axes))
    res = simulate(sc)  # the sweep's 38 s: from 0.7 R2 the law needs them
    m = res.metrics()
    assert m["verdict"] == "ok"
    assert abs(m["R2_error_pct"]) < 0.5
    assert m["R2_held_pct"] < 20.0
    ripple = _tail(res, "speed_est_rpm", 3.0) - _tail(res, "speed_ref_rpm", 3.0)
    assert ripple.max() - ripple.min() < 1.0
