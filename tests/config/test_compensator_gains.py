"""The compensator's machine-dependent settings left unset follow the machine
(config/compensator_gains.py): the paper's numbers on Table IV, bit for bit, scaled by the
machine's R2, rated flux, rated slip speed, rated current and the injection frequency
elsewhere; a per-unit twin or an absolute value wins, in that order.
"""

from __future__ import annotations

import math

import pytest

from imdrive.config.perunit import resolve
from imdrive.config.rated import rated_point
from imdrive.config.resolved import resolved_defaults
from imdrive.config.scenario import Scenario

ON = ["compensator.enabled=true"]


def _slip_rpm(m) -> float:
    rp = rated_point(m)
    return rp.synchronous_speed_rpm - rp.speed_rpm


def test_table_iv_keeps_the_paper_numbers_exactly():
    r = resolve(Scenario.read("sensorless", ON))
    assert (r.G_CR, r.gain_E, r.gain_DE) == (0.001, 1e6, 1e6)
    # (the band: 0.75 of the 2 Hz injection since the schedule is its three harmonics; the
    # first release's two-frequency schedule had half, 1 Hz)
    assert (r.gate_speed_rpm, r.gate_iq_A, r.gate_band) == (1.0, 0.3, 1.5)


@pytest.mark.parametrize("machine", ["krause-50hp", "aalto-2.2kw", "krause-2250hp"])
def test_unset_settings_keep_their_share_of_the_machine(machine):
    t4 = Scenario.read("sensorless", ON)
    sc = Scenario.read("sensorless", [*ON, f'machine.preset="{machine}"'])
    r0, r = resolve(t4), resolve(sc)
    m0, m = t4.machine, sc.machine
    assert m.R2_ohm != pytest.approx(m0.R2_ohm, rel=0.1)  # a machine unlike Table IV
    assert r.G_CR / m.R2_ohm == pytest.approx(r0.G_CR / m0.R2_ohm, rel=1e-12)
    for g, g0 in ((r.gain_E, r0.gain_E), (r.gain_DE, r0.gain_DE)):
        assert g * m.rated_flux_Wb == pytest.approx(g0 * m0.rated_flux_Wb, rel=1e-12)
    assert r.gate_speed_rpm / _slip_rpm(m) == pytest.approx(
        r0.gate_speed_rpm / _slip_rpm(m0), rel=1e-12
    )
    assert r.gate_iq_A / m.rated_current_A == pytest.approx(
        r0.gate_iq_A / m0.rated_current_A, rel=1e-12
    )
    assert r.gate_band == pytest.approx(0.75 * r.inj_f1, rel=1e-12)


def test_a_twin_or_an_absolute_value_wins():
    base = [*ON, 'machine.preset="krause-50hp"']
    r = resolve(Scenario.read("sensorless", [*base, "compensator.G_CR_pu=0.01"]))
    assert r.G_CR == pytest.approx(0.01 * r.R2_hat, rel=1e-12)
    r = resolve(Scenario.read("sensorless", [*base, "compensator.G_CR_ohm=0.004"]))
    assert r.G_CR == 0.004
    r = resolve(Scenario.read("sensorless", [*base, "compensator.gate_band_Hz=0.7"]))
    assert r.gate_band == 0.7
    r = resolve(Scenario.read("sensorless", [*base, "compensator.gate_band_pu=0.25"]))
    assert r.gate_band == pytest.approx(0.25 * r.inj_f1, rel=1e-12)


def test_the_paper_presets_get_theirs_and_show_all_names_the_derived_ones():
    sc = Scenario.read("paper-fig5")  # the paper's numbers are the defaults on Table IV
    assert (sc.compensator.G_CR_pu, sc.compensator.gain_E_pu) == (None, None)
    r = resolve(sc)
    assert (r.G_CR, r.gain_E, r.gain_DE) == (0.001, 1e6, 1e6)
    d = resolved_defaults(Scenario.read("sensorless", [*ON, 'machine.preset="krause-50hp"']))
    assert d["compensator.G_CR_ohm"] == pytest.approx(
        0.001
        * Scenario.read("sensorless", ['machine.preset="krause-50hp"']).machine.R2_ohm
        / Scenario.read("sensorless").machine.R2_ohm,
        rel=1e-12,
    )
    text = Scenario.read("sensorless", ON).to_toml()
    assert "# G_CR_ohm is unset (its documented default applies: 0.001 here)" in text
    assert "# gain_E_per_Wb is unset (its documented default applies: 1000000.0 here)" in text
    # a per-unit twin set in the same table is named as the value's source
    twin = Scenario.read("sensorless", [*ON, "compensator.G_CR_pu=0.03"])
    assert "# G_CR_ohm is unset (taken from its twin G_CR_pu: " in twin.to_toml()


INJ = [*ON, "injection.amplitude_pu=0.075"]


@pytest.mark.parametrize("machine", ["krause-50hp", "aalto-2.2kw", "krause-2250hp"])
def test_the_unset_injection_frequency_follows_the_rotor_corner(machine):
    t4 = resolve(Scenario.read("sensorless", INJ))
    assert (t4.inj_f1, t4.inj_f2, t4.n_comp) == (2.0, 4.0, 5000)  # Table IV, bit for bit
    sc = Scenario.read("sensorless", [*INJ, f'machine.preset="{machine}"'])
    r = resolve(sc)
    corner = 1.0 / (2.0 * math.pi * sc.machine.T2_s)
    corner_t4 = 1.0 / (2.0 * math.pi * Scenario.read("sensorless").machine.T2_s)
    # the same multiple of the corner, to within the rounding to whole control periods
    Ts = sc.simulation.Ts_s
    assert r.inj_f1 / corner == pytest.approx(2.0 / corner_t4, abs=r.inj_f1 * Ts * 2.0 / corner)
    assert (1.0 / (r.inj_f1 * Ts)) == pytest.approx(round(1.0 / (r.inj_f1 * Ts)), abs=1e-6)
    assert (r.inj_f2, r.inj_f3) == (2.0 * r.inj_f1, 3.0 * r.inj_f1)
    assert r.gate_band == 0.75 * r.inj_f1
    assert resolved_defaults(sc)["injection.frequency_Hz"] == r.inj_f1
    # given, it is used as it is
    given = resolve(
        Scenario.read(
            "sensorless", [*INJ, f'machine.preset="{machine}"', "injection.frequency_Hz=2.0"]
        )
    )
    assert given.inj_f1 == 2.0
