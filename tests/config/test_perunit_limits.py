"""The controller's current limit and the divergence bound follow the machine's nameplate
current (``config/perunit.py``), checked on every library machine."""

from __future__ import annotations

import math

import pytest

from imdrive.config.machine import machine_presets, rated_point
from imdrive.config.perunit import (
    CURRENT_LIMIT_PU,
    adc_range_A,
    current_limit_A,
    divergence_current_A,
    rated_peak_current_A,
    sign_band_A,
)
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning


def _foc_current_at_rated_torque(m) -> float:
    """Peak stator current a field-oriented drive needs for rated torque at rated flux, A:
    ``id = psi/M``, ``iq = T L2 / (1.5 n_p M psi)``."""
    psi = m.rated_flux_Wb
    i_d = psi / m.M_H
    i_q = rated_point(m).torque_Nm * m.L2_H / (1.5 * m.pole_pairs * m.M_H * psi)
    return math.hypot(i_d, i_q)


@pytest.mark.parametrize("name", sorted(machine_presets()))
def test_current_limit_is_1p5_times_the_nameplate_peak_current(name):
    sc = Scenario.read("sensorless", [f"machine.preset={name}"])
    rp = rated_point(sc.machine)
    peak = math.sqrt(2.0) * rp.current_rms_A
    assert rated_peak_current_A(sc.machine) == pytest.approx(peak, rel=1e-12)
    assert current_limit_A(sc) == pytest.approx(CURRENT_LIMIT_PU * peak, rel=1e-12)
    # the limit leaves the speed loop rated torque with a margin on every machine
    assert current_limit_A(sc) > 1.2 * _foc_current_at_rated_torque(sc.machine)
    assert divergence_current_A(sc) == pytest.approx(70.0 * peak, rel=1e-12)


def test_table_iv_limit_and_the_explicit_keys():
    sc = Scenario.read("sensorless")
    assert current_limit_A(sc) == pytest.approx(1.5 * math.sqrt(2) * 8.11, rel=2e-3)  # 17.2 A
    given = Scenario.read(
        "sensorless", ["control.current_limit_A=12", "simulation.divergence_current_A=99"]
    )
    assert current_limit_A(given) == 12.0 and divergence_current_A(given) == 99.0


def test_the_drive_runs_on_that_limit():
    from imdrive.run.build import build_arrays

    sc = Scenario.read("sensorless", ["machine.preset=aalto-2.2kw"])
    P = build_arrays(sc).params
    assert float(P.control["i_max"][0]) == pytest.approx(current_limit_A(sc), rel=1e-12)
    # the old default, 2 sqrt(2) P / (sqrt(3) V) = 8.98 A, was only 1.27 x its 7.07 A peak
    assert current_limit_A(sc) == pytest.approx(1.5 * math.sqrt(2) * 5.0, rel=1e-12)


def test_lost_control_duration_stays_absolute():
    """``simulation.lost_control_s`` stays 1 s whatever the machine. Scaled by the mechanical
    time constant J w_rated / T_rated it would be 1.00 s on Table IV but 7.3 s with a 0.5 kg m^2
    rotor, hiding exactly the loss of control a too-large inertia causes (the drive cannot
    follow the ramp: tests/cli/test_console.py, test_ramp_beyond_the_current_limit_is_named)."""
    for name in sorted(machine_presets()):
        assert (
            Scenario.read("sensorless", [f"machine.preset={name}"]).simulation.lost_control_s == 1.0
        )
    m = Scenario.read("sensorless", ["machine.J_kgm2=0.5"]).machine
    rp = rated_point(m)
    assert m.J_kgm2 * rp.speed_rpm * math.pi / 30.0 / rp.torque_Nm > 7.0


def test_preset_times_too_short_for_the_machine_are_warned_of_without_the_sequencing():
    import warnings

    from imdrive.errors import ConfigWarning

    # the drive premagnetises and limits its ramps by itself (config/sequence.py): no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConfigWarning)
        for name in ("paper-table-iv", "krause-50hp", "aalto-2.2kw", "krause-2250hp"):
            _with_machine(name)
        Scenario.read("sensorless", ["machine.J_kgm2=0.5"])
    off = ["control.premagnetise_T2=1", "control.ramp_torque_limit=false"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConfigWarning)
        for name in ("paper-table-iv", "krause-50hp", "aalto-2.2kw"):  # 3 T2 <= 0.5 s
            _with_machine(name, off)
    with pytest.warns(ConfigWarning, match=r"before the rotor is magnetised.* 4\.8 s"):
        _with_machine("krause-2250hp", off)  # T2 = 1.6 s
    with pytest.warns(ConfigWarning, match=r"asks more than the rated torque .* 1\.68 s"):
        _with_machine("geyer-3.3kv", off)  # J w / T = 1.0 s per 596 rpm
    with pytest.warns(ConfigWarning, match="give it at least 4.22 s"):
        Scenario.read("sensorless", ["machine.J_kgm2=0.5", *off])  # 0 -> 1000 rpm in 1 s: 52 N m
    # times too short for Table IV as well are the scenario's own choice: no warning
    ramp = "control.speed_ref_rpm={initial=0,changes=[{at=0.05,to=1000,over=0.3}]}"
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConfigWarning)
        Scenario.read("sensorless", [ramp, *off])
        Scenario.read("sensorless", [ramp, "machine.preset=krause-2250hp", *off])


def _with_machine(name, extra=()):
    """The sensorless preset on machine ``name``, its profiles in rpm and N m as they were."""
    rpm = "control.speed_ref_rpm={initial=0,changes=[{at=0.5,to=1000,over=1.0}]}"
    load = "load.torque_Nm={initial=0,changes=[{at=2.0,to=12}]}"
    return Scenario.read("vector-sensored", [f"machine.preset={name}", rpm, load, *extra])


@pytest.mark.parametrize("name", sorted(machine_presets()))
def test_adc_full_scale_follows_the_rated_current(name):
    sc = Scenario.read("sensorless", [f"machine.preset={name}", "sensor.adc_bits=12"])
    I_peak = rated_peak_current_A(sc.machine)
    I_tab4 = rated_peak_current_A(Scenario.read("sensorless").machine)
    # Table IV's 50 A, in the same ratio to every machine's rated peak current
    assert adc_range_A(sc) == pytest.approx(50.0 * I_peak / I_tab4, rel=1e-12)
    assert adc_range_A(sc) / I_peak == pytest.approx(4.362, rel=1e-3)
    assert adc_range_A(sc) > 2.9 * current_limit_A(sc)  # the limit is never clipped
    with pytest.warns(ConfigWarning, match="replaces sensor.adc_range_A = 50"):
        pu = sc.with_overrides(["sensor.adc_range_A=50"]).with_overrides(["sensor.adc_range_pu=3"])
    assert adc_range_A(pu) == pytest.approx(3.0 * I_peak, rel=1e-12)


def test_adc_full_scale_on_table_iv_is_exactly_50_A():
    assert adc_range_A(Scenario.read("sensorless")) == 50.0
    # the absolute key of the last release still sets it
    assert adc_range_A(Scenario.read("sensorless", ["sensor.adc_range_A=20"])) == 20.0
    # the realistic presets leave it derived: 50 A on Table IV, following another machine
    assert adc_range_A(Scenario.read("sensorless-realistic")) == 50.0
    big = Scenario.read("sensorless-realistic", ["machine.preset=krause-2250hp"])
    assert big.sensor.adc_range_A is None
    assert adc_range_A(big) == pytest.approx(
        50.0 * rated_peak_current_A(big.machine) / 11.4629, rel=1e-4
    )


def test_sign_band_follows_the_rated_current_as_the_ripple_does():
    assert sign_band_A(Scenario.read("sensorless")) == 0.2  # Table IV: exactly as before
    ripple_pu, ripple_A = [], []
    for name in sorted(machine_presets()):
        sc = Scenario.read("sensorless", [f"machine.preset={name}"])
        m, I_peak = sc.machine, rated_peak_current_A(sc.machine)
        assert sign_band_A(sc) / I_peak == pytest.approx(0.2 / 11.4629, rel=1e-4)
        ripple = sc.inverter.Vdc_V * sc.simulation.Ts_s / (m.sigma * (m.Ll1_H + m.M_H))
        ripple_A.append(ripple)
        ripple_pu.append(ripple / I_peak)
    # the commutation ripple the band stands for: a few tenths of the rated current on every
    # machine, where in amperes it spans two decades
    assert 0.2 < min(ripple_pu) and max(ripple_pu) < 0.7
    assert 2.5 < min(ripple_A) and max(ripple_A) > 270.0
    sc = Scenario.read("sensorless", ["inverter.sign_band_pu=0.05"])
    assert sign_band_A(sc) == pytest.approx(0.05 * rated_peak_current_A(sc.machine))
    with pytest.warns(ConfigWarning, match="replaces inverter.sign_band_A = 0.2"):
        sc = Scenario.read("sensorless", ["inverter.sign_band_A=0.2"]).with_overrides(
            ["inverter.sign_band_pu=0.05"]
        )
    assert sc.inverter.sign_band_A is None
