"""The steady state of a drive scenario (imdrive.analysis.drive_steady_state): the detuning law
vanishes with R2_hat = R2 and follows the slip's sign and size, the rated point's stator
frequency is the nameplate's, and the old import path (imdrive.studies.machines) still works."""

from __future__ import annotations

import math

import pytest

from imdrive.analysis import drive_steady_state as ss
from imdrive.config.machine import rated_point
from imdrive.config.scenario import Scenario


@pytest.mark.parametrize("machine", ["paper-table-iv", "aalto-2.2kw", "krause-50hp"])
def test_half_speed_at_rated_torque_follows_the_slip_relation(machine):
    """Below the rated voltage the drive runs the rated flux, and rotor-flux orientation's
    slip ``w_sl = R2 T_e / (1.5 n_p psi_r^2)`` (``T_e`` the load plus friction) gives both the
    stator frequency ``(n_p w_m + w_sl)/2 pi`` and the detuning law ``slip (R2_hat/R2 - 1)``
    (Krishnan, *Electric Motor Drives*, Prentice Hall, 2001, ch. 8)."""
    sc = Scenario.read("sensorless", [f'machine.preset="{machine}"'])
    m = sc.machine
    rp = rated_point(m)
    n, T = 0.5 * rp.speed_rpm, rp.torque_Nm
    w_m = n * math.pi / 30.0
    psi = ss.law_flux_Wb(sc, n, T, 1.0)
    assert psi == pytest.approx(m.rated_flux_Wb)
    w_sl = m.R2_ohm * (T + m.B_Nms * w_m) / (1.5 * m.pole_pairs * psi**2)
    f_s = (m.pole_pairs * w_m + w_sl) / (2.0 * math.pi)
    assert ss.stator_frequency_Hz(sc, n, T, 1.0) == pytest.approx(f_s, rel=1e-3)
    assert ss.detuning_law_rpm(sc, n, T, 1.0) == pytest.approx(0.0, abs=1e-6)
    slip_rpm = w_sl / m.pole_pairs * 30.0 / math.pi
    assert ss.detuning_law_rpm(sc, n, T, 1.2) == pytest.approx(0.2 * slip_rpm, rel=1e-3)


def test_the_old_import_path_is_the_same_function():
    from imdrive.studies import machines

    for name in ("law_flux_Wb", "detuning_law_rpm", "stator_frequency_Hz"):
        assert getattr(machines, name) is getattr(ss, name)
