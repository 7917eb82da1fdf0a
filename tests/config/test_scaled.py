"""Machine-dependent defaults first tuned in SI on Table IV, scaled to the scenario's machine
(``config/scaled.py``): exactly the old number on Table IV, in proportion to the machine's base
quantity on the others, the old absolute key still taken as given and declared with its
per-unit twin in ``config/pairs.py``."""

from __future__ import annotations

import math

import pytest

from imdrive.config.pairs import pair_of
from imdrive.config.perunit import rated_peak_current_A
from imdrive.config.scaled import (
    EKF_NOISE,
    ekf_noise,
    rated_acceleration_rad_s2,
    rated_phase_peak_V,
    rotor_flux_rate_Wb_s,
    rotor_resistance_rate_ohm_s,
)
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError, ConfigWarning

OTHERS = ("krause-500hp", "aalto-2.2kw")


def _ekf(machine: str = "paper-table-iv", *overrides: str) -> Scenario:
    return Scenario.read(
        "sensorless", [f"machine.preset={machine}", 'control.speed_feedback="ekf"', *overrides]
    )


# -- the EKF's noise ------------------------------------------------------------------------


def test_ekf_noise_on_table_iv_is_exactly_the_old_tuning():
    assert ekf_noise(_ekf().ekf, _ekf().machine) == (5.0, 0.1, 2000.0, 0.5, 0.05)


def test_ekf_records_on_table_iv_are_those_of_the_old_numbers():
    from imdrive.run.build import build_arrays

    old = [f"ekf.{k}={v}" for k, _, v, _ in EKF_NOISE]
    new, given = build_arrays(_ekf()).params.est[0], build_arrays(_ekf("paper-table-iv", *old))
    assert list(new["q"]) == list(given.params.est[0]["q"])  # bit for bit
    assert new["r"] == given.params.est[0]["r"] == 0.05**2


@pytest.mark.parametrize("machine", OTHERS)
def test_ekf_noise_scales_with_the_quantity_each_stands_for(machine):
    iv, m = _ekf().machine, _ekf(machine).machine
    got = ekf_noise(_ekf(machine).ekf, m)
    assert got[0] > 1.8 * 5.0 and got[4] != pytest.approx(0.05, rel=0.3)  # the numbers move
    bases = (
        rated_phase_peak_V,
        rotor_flux_rate_Wb_s,
        rated_acceleration_rad_s2,
        rotor_resistance_rate_ohm_s,
        rated_peak_current_A,
    )
    for value, (absolute, _, table_iv, _), base in zip(got, EKF_NOISE, bases, strict=True):
        assert value / base(m) == pytest.approx(table_iv / base(iv), rel=1e-12), absolute


def test_ekf_bases_are_the_machine_quantities_named():
    m = _ekf("aalto-2.2kw").machine
    assert rated_phase_peak_V(m) == pytest.approx(400.0 * math.sqrt(2.0 / 3.0))
    from imdrive.config.machine import rated_point

    rp = rated_point(m)
    assert rated_acceleration_rad_s2(m) == pytest.approx(m.pole_pairs * rp.torque_Nm / m.J_kgm2)
    assert rotor_flux_rate_Wb_s(m) == pytest.approx(m.rated_flux_Wb * m.R2_ohm / m.L2_H)
    assert rotor_resistance_rate_ohm_s(m) == pytest.approx(m.R2_ohm**2 / m.L2_H)
    # the rated acceleration follows the inertia: twice J, half the acceleration noise
    sc = _ekf("aalto-2.2kw")
    heavy = _ekf("aalto-2.2kw", f"machine.J_kgm2={2 * m.J_kgm2}")
    assert ekf_noise(heavy.ekf, heavy.machine)[2] == pytest.approx(
        0.5 * ekf_noise(sc.ekf, sc.machine)[2]
    )


@pytest.mark.parametrize(("absolute", "per_unit", "table_iv", "base"), EKF_NOISE)
def test_ekf_old_absolute_keys_work_and_are_paired(absolute, per_unit, table_iv, base):
    pair = pair_of(f"ekf.{absolute}")
    assert pair is not None and pair.per_unit == (f"ekf.{per_unit}",)
    i = [n for n, *_ in EKF_NOISE].index(absolute)
    sc = _ekf("krause-500hp", f"ekf.{absolute}={table_iv}")
    assert ekf_noise(sc.ekf, sc.machine)[i] == table_iv  # as given, on any machine
    sc = _ekf("krause-500hp", f"ekf.{per_unit}=0.01")
    assert ekf_noise(sc.ekf, sc.machine)[i] == pytest.approx(0.01 * base(sc.machine))
    with pytest.raises(ConfigError, match=f"ekf.{per_unit}"):
        _ekf("paper-table-iv", f"ekf.{absolute}=1", f"ekf.{per_unit}=0.01")
    with pytest.warns(ConfigWarning, match=f"replaces ekf.{absolute}"):
        sc = _ekf("paper-table-iv", f"ekf.{absolute}=1").with_overrides([f"ekf.{per_unit}=0.01"])
    assert getattr(sc.ekf, absolute) is None
