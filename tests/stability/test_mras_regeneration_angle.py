"""The MRAS's rotated adaptation error in the plugging quadrant (mras_stabilise.py).

Regenerating at 20 rpm (the stator frequency against the speed) the linearised sensorless loop
has a pole in the right half-plane with Schauder's error and none with the rotated one, on two
machines of the library; where the stator frequency is with the speed (motoring) the rotation is
zero and the loop is the same to the last digit.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from imdrive.config.machine import rated_point
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning
from imdrive.kernels.estimators.mras import MRAS_PARAMS
from imdrive.kernels.estimators.mras_stabilise import adaptation_error, regeneration_angle
from imdrive.kernels.records import new_record
from imdrive.stability.linear import map_scenario, operating_point


def _point(machine: str, speed_pu: float, load_pu: float, angle_deg: float | None):
    """The sensorless drive on ``machine`` linearised at a speed and load in per-unit, R2_hat = R2
    (``angle_deg`` None: the default rotation)."""
    ov = [f'machine.preset="{machine}"']
    if angle_deg is not None:
        ov.append(f"mras.regeneration_angle_deg={angle_deg}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        sc = Scenario.read("sensorless", ov)
    rp = rated_point(sc.machine)
    op = operating_point(
        map_scenario(sc, R2_ratio=1.0), speed_pu * rp.speed_rpm, load_pu * rp.torque_Nm
    )
    assert op.status == "ok"
    return op


@pytest.mark.parametrize(
    "machine, speed_pu, load_pu",
    [("paper-table-iv", 0.0116, -0.5), ("krause-50hp", 0.0116, -0.5)],
)
def test_rotation_moves_the_regenerating_pole_into_the_left_half_plane(machine, speed_pu, load_pu):
    plain = _point(machine, speed_pu, load_pu, 0.0).modes()[0].s.real
    rotated = _point(machine, speed_pu, load_pu, None).modes()[0].s.real
    # measured: Table IV +3.8 -> -3.5 /s, Krause 50 hp +5.5 -> -1.6 /s
    assert plain > 1.0
    assert rotated < -0.5


def test_motoring_loop_unchanged_by_the_rotation():
    plain = _point("paper-table-iv", 0.0116, 0.5, 0.0)
    rotated = _point("paper-table-iv", 0.0116, 0.5, None)
    np.testing.assert_array_equal(plain.A, rotated.A)


def _params(angle_deg=80.0, band=2.0, speed=1.0):
    return new_record(
        MRAS_PARAMS, phi_max=math.radians(angle_deg), phi_w_band=band, phi_w_speed=speed
    )[0]


def _turning(w_e, Ts=1e-4):
    """Two samples of a 0.5 Wb flux turning at ``w_e`` rad/s over one period ``Ts``."""
    return 0.5 + 0j, 0.5 * complex(math.cos(w_e * Ts), math.sin(w_e * Ts)), Ts


def test_angle_full_against_the_speed_zero_with_it_and_of_the_speed_sign():
    p = _params()
    assert regeneration_angle(p, 10.0, *_turning(-5.0)) == pytest.approx(math.radians(80.0))
    assert regeneration_angle(p, -10.0, *_turning(5.0)) == pytest.approx(-math.radians(80.0))
    assert regeneration_angle(p, 10.0, *_turning(1.0)) == 0.0  # w_e >= band/2 with the speed
    assert regeneration_angle(p, -10.0, *_turning(-3.0)) == 0.0
    # half-way on the ramp, and continuous through zero speed
    assert regeneration_angle(p, 10.0, *_turning(0.0)) == pytest.approx(math.radians(40.0))
    assert regeneration_angle(p, 0.0, *_turning(-5.0)) == 0.0
    assert regeneration_angle(_params(angle_deg=0.0), 10.0, *_turning(-5.0)) == 0.0


def test_rotated_error_is_the_cross_product_at_zero_and_zero_where_the_models_agree():
    lv, lf = (0.3, 0.4), (0.35, 0.38)
    cross = lv[1] * lf[0] - lv[0] * lf[1]
    assert adaptation_error(*lv, *lf, 0.0) == cross
    # the models agree: no error whatever the angle (the error vector is rotated, not lam_v)
    assert adaptation_error(*lf, *lf, 1.2) == pytest.approx(0.0, abs=1e-15)
    # a pure magnitude mismatch is read only through the angle: -sin(phi) Re{d conj(lam_f)}
    big = (1.1 * lf[0], 1.1 * lf[1])
    dot = 0.1 * (lf[0] ** 2 + lf[1] ** 2)
    assert adaptation_error(*big, *lf, 0.5) == pytest.approx(-math.sin(0.5) * dot)
