"""Stability maps of the type-2 MRAS (``mras.acceleration_tracking``): its second integrator
in the reduced state where it runs (kernels/linearise.py), held at 0 where it does not."""

from __future__ import annotations

import numpy as np
import pytest

import imdrive.kernels.linearise as kl
from imdrive.config.rated import rated_point
from imdrive.config.scenario import Scenario
from imdrive.run.build import build_arrays
from imdrive.stability.linear import operating_point
from imdrive.stability.maps import validate_map

MACHINES = ("krause-50hp", "aalto-2.2kw", "krause-500hp")


def _type2(machine: str) -> Scenario:
    return Scenario.read(
        "sensorless", [f'machine.preset="{machine}"', "mras.acceleration_tracking=true"]
    )


@pytest.mark.parametrize("machine", MACHINES)
@pytest.mark.parametrize("speed_pu, load_pu", [(0.8, 0.5), (0.02, 0.5), (0.5, -0.5)])
def test_the_fixed_point_and_its_second_integrator(machine, speed_pu, load_pu):
    """Running (above b2_wmin): the PI's output is 0 at the fixed point and the estimate is
    ``b2`` times the second integrator; held (at 2 % of the rated speed): the state is 0 and
    the eigenvalue it adds is 0, not the neutral 1."""
    sc = _type2(machine)
    rp = rated_point(sc.machine)
    op = operating_point(sc, speed_pu * rp.speed_rpm, load_pu * rp.torque_Nm)
    assert op.status == "ok"
    b2 = float(build_arrays(sc).params.est[0]["b2"])
    assert b2 > 0.0
    if speed_pu > 0.1:
        assert op.z[21] * b2 == pytest.approx(op.z[20], rel=1e-6)
    else:
        assert op.z[21] == 0.0
        assert np.all(np.abs(op.A[21]) == 0.0)
    assert np.max(np.abs(np.linalg.eigvals(op.A))) < 1.0


@pytest.mark.slow
@pytest.mark.parametrize("machine", MACHINES[:2])
def test_the_linearisation_matches_the_nonlinear_responses(machine):
    """A^n dz and the input responses against the engine's own run, to 1e-3 relative (as
    the type-1 MRAS's in tests/stability/test_stability.py)."""
    sc = _type2(machine)
    rp = rated_point(sc.machine)
    op = operating_point(sc, 0.8 * rp.speed_rpm, 0.5 * rp.torque_Nm)
    scale = np.abs(op.z) + kl.Z_SCALE
    rng = np.random.default_rng(3)
    worst = 0.0
    for n in (1, 10, 100, 400):
        dz = 1e-6 * rng.standard_normal(kl.N_Z) * scale
        lin = np.linalg.matrix_power(op.A, n) @ dz
        nl = op.propagate(dz, n)
        worst = max(worst, np.linalg.norm((nl - lin) / scale) / np.linalg.norm(lin / scale))
    assert worst < 1e-3


@pytest.mark.slow
def test_the_map_agrees_with_the_time_domain_at_the_rated_point_of_each_machine():
    """The map's verdict at rated speed and torque, motoring and regenerating, against a
    speed-reference step simulated from the fixed point (validate_map), on the library
    machines with the type-2 MRAS."""
    for machine in MACHINES:
        sc = _type2(machine)
        rp = rated_point(sc.machine)
        table, _ = validate_map(sc, [rp.speed_rpm], [-rp.torque_Nm, rp.torque_Nm], horizon_s=1.0)
        ok = table[table["status"] == "ok"]
        assert len(ok) >= 1, machine
        assert (ok["stable"] == ok["sim_stable"]).all(), (machine, ok)


def test_the_map_linearises_field_weakening_at_its_flux_and_says_so():
    """Above base speed a drive with field weakening holds a point the reference flux cannot
    reach at a lowered flux: the map linearises it there (``flux_factor`` below 1) and says
    so; without field weakening the point stays ``voltage_limit`` and the map says nothing."""
    from imdrive.stability.maps import stability_map

    for fw in (True, False):
        sc = Scenario.read(
            "sensorless",
            ['machine.preset="krause-50hp"', f"control.field_weakening={str(fw).lower()}"],
        )
        rp = rated_point(sc.machine)
        m = stability_map(sc, [0.5 * rp.speed_rpm, 1.5 * rp.speed_rpm], [0.5 * rp.torque_Nm])
        below, above = m.iloc[0], m.iloc[1]
        assert below["status"] == "ok" and below["flux_factor"] == 1.0
        note = m.attrs["note"]
        if fw:
            # at 1.5 x the rated speed the flux falls roughly as 1/speed
            assert above["status"] == "ok" and 0.5 < above["flux_factor"] < 0.8, above
            assert "flux_factor" in note
        else:
            assert above["status"] == "voltage_limit" and above["flux_factor"] == 1.0
            assert note is None
