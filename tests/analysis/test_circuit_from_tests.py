"""The circuit from a no-load and a locked-rotor test: tests measured on a known circuit give
that circuit back."""

from __future__ import annotations

import math

import pytest

from imdrive import machine_preset, machine_presets
from imdrive.analysis.circuit import equivalent_circuit
from imdrive.analysis.circuit_from_tests import LockedRotorTest, NoLoadTest, circuit_from_tests
from imdrive.errors import ConfigError


def _tests(m, f_k_ratio=0.25, I_k_ratio=1.0):
    """The two tests measured on circuit ``m`` (phasor steady state): no load at rated voltage
    and frequency (slip 0), locked rotor at ``f_k_ratio`` of the frequency, with the voltage
    that drives about the rated current."""
    V, f = m.rated_voltage_V, m.rated_frequency_Hz
    nl = equivalent_circuit(m, V, f, 0.0)
    P0 = 1.5 * (nl.V1 * nl.I1.conjugate()).real
    f_k = f_k_ratio * f
    probe = equivalent_circuit(m, V, f_k, 1.0)
    from imdrive.config.machine import rated_point

    V_k = V * I_k_ratio * rated_point(m).current_rms_A / probe.I1_rms_A
    lr = equivalent_circuit(m, V_k, f_k, 1.0)
    Pk = 1.5 * (lr.V1 * lr.I1.conjugate()).real
    return (
        NoLoadTest(V, float(nl.I1_rms_A), float(P0), f),
        LockedRotorTest(V_k, float(lr.I1_rms_A), float(Pk), f_k),
    )


@pytest.mark.parametrize("f_k_ratio", [1.0, 0.25])
@pytest.mark.parametrize("name", list(machine_presets()))
def test_tests_on_a_circuit_give_that_circuit_back(name, f_k_ratio):
    m = machine_preset(name)
    nl, lr = _tests(m, f_k_ratio)
    k = m.Ll1_H / (m.Ll1_H + m.Ll2_H)
    c = circuit_from_tests(m.R1_ohm, nl, lr, leakage_split=k)
    w = 2 * math.pi * m.rated_frequency_Hz
    assert c.R2 == pytest.approx(m.R2_ohm, rel=1e-8)
    assert c.X1 == pytest.approx(w * m.Ll1_H, rel=1e-8)
    assert c.X2 == pytest.approx(w * m.Ll2_H, rel=1e-8)
    assert c.XM == pytest.approx(w * m.M_H, rel=1e-8)
    assert abs(c.iron_loss_W) < 1e-6 * nl.power_W + 1e-9  # the circuit has none


def test_the_usual_approximation_is_what_the_exact_reduction_corrects():
    """Neglecting the magnetising branch at standstill (X1 + X2 = X_k, R2 = R_k - R1) puts R2
    off by several per cent on the 2.2 kW machine; the reduction meets it."""
    m = machine_preset("aalto-2.2kw")
    nl, lr = _tests(m, 1.0)
    Rk = lr.power_W / (3 * lr.current_A**2)
    assert abs((Rk - m.R1_ohm) / m.R2_ohm - 1) > 0.05
    c = circuit_from_tests(m.R1_ohm, nl, lr)
    assert c.R2 == pytest.approx(m.R2_ohm, rel=1e-8)


def test_friction_and_windage_leave_the_iron_loss():
    m = machine_preset("krause-50hp")
    nl, lr = _tests(m)
    nl2 = NoLoadTest(nl.voltage_V, nl.current_A, nl.power_W + 500.0, nl.frequency_Hz, 200.0)
    c = circuit_from_tests(m.R1_ohm, nl2, lr)
    assert c.iron_loss_W == pytest.approx(300.0, abs=1e-6)


@pytest.mark.parametrize(
    "change, field",
    [
        (dict(R1_ohm=-1.0), "R1_ohm"),
        (dict(R1_ohm=100.0), "locked_rotor.power_W"),  # P_k / 3 I_k^2 below R1
        (dict(nl_power=1e9), "no_load.power_W"),
    ],
)
def test_impossible_tests_are_refused_naming_the_field(change, field):
    m = machine_preset("krause-3hp")
    nl, lr = _tests(m)
    if "nl_power" in change:
        nl = NoLoadTest(nl.voltage_V, nl.current_A, change["nl_power"], nl.frequency_Hz)
    with pytest.raises(ConfigError) as err:
        circuit_from_tests(change.get("R1_ohm", m.R1_ohm), nl, lr)
    assert err.value.field == field
