"""Machine-dependent defaults first tuned in SI on Table IV, scaled to the scenario's machine
(``config/scaled.py``): exactly the old number on Table IV, in proportion to the machine's base
quantity on the others, the old absolute key still taken as given and declared with its
per-unit twin in ``config/pairs.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imdrive.config.pairs import pair_of
from imdrive.config.perunit import rated_peak_current_A
from imdrive.config.scaled import (
    EKF_NOISE,
    RISE_BASE_K,
    afo_resistance_bandwidths,
    ekf_noise,
    flux_injection_frequency_Hz,
    plant_thermal_resistances,
    rated_acceleration_rad_s2,
    rated_copper_losses_W,
    rated_phase_peak_V,
    rotor_corner_Hz,
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


# -- the plant's thermal model ----------------------------------------------------------------


def _thermal(machine: str = "paper-table-iv", *overrides: str) -> Scenario:
    return Scenario.read(
        "sensorless", [f"machine.preset={machine}", "plant.thermal.enabled=true", *overrides]
    )


def test_plant_thermal_resistances_on_table_iv_are_exactly_the_old_ones():
    from imdrive.run.build import build_arrays

    assert plant_thermal_resistances(_thermal()) == (0.4, 0.4)
    plant = build_arrays(_thermal()).params.plant[0]
    assert (plant["Rth1"], plant["Rth2"]) == (0.4, 0.4)
    # the time constants stay absolute (no published scaling with the machine's size)
    assert (_thermal().plant.thermal.tau1_s, _thermal().plant.thermal.tau2_s) == (1200.0, 1200.0)


@pytest.mark.parametrize("machine", OTHERS)
def test_plant_thermal_resistance_gives_table_iv_s_rise_at_rated_losses(machine):
    from imdrive.run.build import build_arrays

    sc = _thermal(machine)
    Rth = plant_thermal_resistances(sc)
    losses, losses_iv = rated_copper_losses_W(sc.machine), rated_copper_losses_W(_thermal().machine)
    for i in range(2):
        # the steady rise at the winding's rated losses is Table IV's (34 K stator, 41 K rotor)
        assert Rth[i] * losses[i] == pytest.approx(0.4 * losses_iv[i], rel=1e-12)
        assert not math.isclose(Rth[i], 0.4, rel_tol=0.05)
    assert 0.4 * losses_iv[1] == pytest.approx(41.1, abs=0.1)
    plant = build_arrays(sc).params.plant[0]
    assert (plant["Rth1"], plant["Rth2"]) == Rth  # what the plant runs on


def test_rated_copper_losses_are_the_rated_point_s():
    from imdrive.config.machine import rated_point
    from imdrive.config.perunit import rated_rotor_loss_W

    sc = _thermal("aalto-2.2kw", "compensator.thermal_model=true")
    p1, p2 = rated_copper_losses_W(sc.machine)
    assert p1 == pytest.approx(
        1.5 * sc.machine.R1_ohm * rated_point(sc.machine).current_peak_A ** 2
    )
    assert p2 == rated_rotor_loss_W(sc)  # the compensator's thermal model's base
    # the base rise is the compensator's default class B rise
    assert RISE_BASE_K == Scenario.read("sensorless").compensator.thermal_rise_K


@pytest.mark.parametrize("n", ("1", "2"))
def test_plant_thermal_old_absolute_keys_work_and_are_paired(n):
    absolute, per_unit = f"plant.thermal.Rth{n}_K_per_W", f"plant.thermal.Rth{n}_pu"
    assert pair_of(absolute).per_unit == (per_unit,)
    i = int(n) - 1
    assert plant_thermal_resistances(_thermal("krause-500hp", f"{absolute}=0.4"))[i] == 0.4
    sc = _thermal("krause-500hp", f"{per_unit}=0.5")
    loss = rated_copper_losses_W(sc.machine)[i]
    assert plant_thermal_resistances(sc)[i] == pytest.approx(0.5 * RISE_BASE_K / loss)
    with pytest.raises(ConfigError, match=per_unit):
        _thermal("paper-table-iv", f"{absolute}=1", f"{per_unit}=0.5")
    with pytest.warns(ConfigWarning, match=f"replaces {absolute}"):
        sc = _thermal("paper-table-iv", f"{absolute}=1").with_overrides([f"{per_unit}=0.5"])
    table_iv_loss = rated_copper_losses_W(sc.machine)[i]
    assert plant_thermal_resistances(sc)[i] == pytest.approx(0.5 * RISE_BASE_K / table_iv_loss)


def test_plant_thermal_model_without_a_rated_point_names_the_setting():
    # a circuit whose rated point cannot be found: the thermal model asks for Rth in K/W
    from imdrive.config.machine import machine_preset

    m = machine_preset("paper-table-iv")
    sc = Scenario.read("sensorless")
    with pytest.raises(ConfigError, match="plant.thermal.enabled"):
        rated_copper_losses_W(m.with_(rated_power_W=1e9))
    assert plant_thermal_resistances(
        _thermal(
            "paper-table-iv", "plant.thermal.Rth1_K_per_W=0.3", "plant.thermal.Rth2_K_per_W=0.2"
        )
    ) == (0.3, 0.2)
    assert sc.plant.thermal.Rth1_K_per_W is None


# -- the flux-command injection's frequency ---------------------------------------------------


def _afo(machine: str = "paper-table-iv", *overrides: str) -> Scenario:
    return Scenario.read(
        "sensorless",
        [
            f"machine.preset={machine}",
            'control.speed_feedback="afo"',
            "flux_injection.amplitude=0.1",
            *overrides,
        ],
    )


@pytest.mark.parametrize("start", ("estimator.R2_ratio=1.0", "estimator.R2_ratio=1.3"))
def test_flux_injection_on_table_iv_is_exactly_2_Hz_whatever_the_start(start):
    from imdrive.run.build import build_arrays

    sc = _afo("paper-table-iv", start)
    assert flux_injection_frequency_Hz(sc) == 2.0
    new, old = (
        build_arrays(sc),
        build_arrays(_afo("paper-table-iv", start, "flux_injection.frequency_Hz=2")),
    )
    assert new.params.sim[0]["flux_inj_freq"] == 2.0
    for f in new.params.est.dtype.names:  # the AFO's gains designed on it: bit for bit
        assert np.array_equal(new.params.est[f], old.params.est[f]), f


@pytest.mark.parametrize("machine", OTHERS)
def test_flux_injection_frequency_is_a_fixed_multiple_of_the_rotor_corner(machine):
    sc, iv = _afo(machine), _afo()
    f, f_iv = flux_injection_frequency_Hz(sc), flux_injection_frequency_Hz(iv)
    # w T2 the same as Table IV's: 1.098 x the corner
    assert f * sc.machine.T2_s == pytest.approx(f_iv * iv.machine.T2_s, rel=1e-12)
    assert f / rotor_corner_Hz(sc.machine) == pytest.approx(1.0980, abs=1e-4)
    assert not math.isclose(f, 2.0, rel_tol=0.05)


def test_flux_injection_old_key_works_and_is_paired():
    assert pair_of("flux_injection.frequency_Hz").per_unit == ("flux_injection.frequency_pu",)
    assert flux_injection_frequency_Hz(_afo("krause-500hp", "flux_injection.frequency_Hz=2")) == 2.0
    # the per-unit twin: of the controller's corner R2_hat(0)/(2 pi L2_hat), as injection's
    sc = _afo("krause-500hp", "estimator.R2_ratio=1.2", "flux_injection.frequency_pu=0.5")
    m = sc.machine
    assert flux_injection_frequency_Hz(sc) == pytest.approx(
        0.5 * 1.2 * m.R2_ohm / (2 * math.pi * m.L2_H)
    )
    with pytest.raises(ConfigError, match="flux_injection.frequency_pu"):
        _afo("paper-table-iv", "flux_injection.frequency_Hz=3", "flux_injection.frequency_pu=1")
    with pytest.warns(ConfigWarning, match="replaces flux_injection.frequency_Hz"):
        sc = _afo("paper-table-iv", "flux_injection.frequency_Hz=3").with_overrides(
            ["flux_injection.frequency_pu=1"]
        )
    assert flux_injection_frequency_Hz(sc) == pytest.approx(rotor_corner_Hz(sc.machine))


# -- the AFO's resistance adaptation rates ----------------------------------------------------


def test_afo_resistance_rates_on_table_iv_are_exactly_2_rad_s():
    from imdrive.run.build import build_arrays

    sc = _afo("paper-table-iv", 'estimator.R2_adaptation="afo"', "afo.R1_adaptation=true")
    assert afo_resistance_bandwidths(sc.afo, sc.machine) == (2.0, 2.0)
    old = _afo(
        "paper-table-iv",
        'estimator.R2_adaptation="afo"',
        "afo.R1_adaptation=true",
        "afo.R1_bandwidth_rad_s=2",
        "afo.R2_bandwidth_rad_s=2",
    )
    new, given = build_arrays(sc).params.est, build_arrays(old).params.est
    for f in ("k_R1", "k_R2", "Kp", "Ki"):
        assert new[f] == given[f], f  # bit for bit


@pytest.mark.parametrize("machine", OTHERS)
def test_afo_resistance_rates_scale_with_the_rotor_corner_below_the_injection(machine):
    sc, iv = _afo(machine), _afo()
    for rate, rate_iv in zip(
        afo_resistance_bandwidths(sc.afo, sc.machine),
        afo_resistance_bandwidths(iv.afo, iv.machine),
        strict=True,
    ):
        assert rate * sc.machine.T2_s == pytest.approx(rate_iv * iv.machine.T2_s, rel=1e-12)
        # as far below the flux injection's angular frequency as on Table IV
        w_inj, w_inj_iv = (2 * math.pi * flux_injection_frequency_Hz(x) for x in (sc, iv))
        assert w_inj / rate == pytest.approx(w_inj_iv / rate_iv, rel=1e-12)
        assert not math.isclose(rate, 2.0, rel_tol=0.05)


@pytest.mark.parametrize("n", ("1", "2"))
def test_afo_old_rate_keys_work_and_are_paired(n):
    absolute, per_unit = f"afo.R{n}_bandwidth_rad_s", f"afo.R{n}_bandwidth_pu"
    assert pair_of(absolute).per_unit == (per_unit,)
    i = int(n) - 1
    sc = _afo("krause-500hp", f"{absolute}=2")
    assert afo_resistance_bandwidths(sc.afo, sc.machine)[i] == 2.0
    sc = _afo("krause-500hp", f"{per_unit}=0.1")
    assert afo_resistance_bandwidths(sc.afo, sc.machine)[i] == pytest.approx(0.1 / sc.machine.T2_s)
    with pytest.raises(ConfigError, match=per_unit):
        _afo("paper-table-iv", f"{absolute}=1", f"{per_unit}=0.1")
    with pytest.warns(ConfigWarning, match=f"replaces {absolute}"):
        sc = _afo("paper-table-iv", f"{absolute}=1").with_overrides([f"{per_unit}=0.1"])
    assert getattr(sc.afo, absolute.split(".")[1]) is None
