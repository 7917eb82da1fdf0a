"""The field weakening's default (config/field_weakening.py): on where the speed reference
takes the drive to the inverter's voltage at the rated torque, off below, as set when set.

Without it the ``sensorless`` preset, its ``[machine]`` replaced, lost control regenerating at
the rated speed on the large machines (tests/drive/test_sensorless_voltage_limit.py runs that
with the default).
"""

from __future__ import annotations

import math
import warnings

import pytest

from imdrive.analysis.foc import foc_operating_point
from imdrive.config.field_weakening import (
    field_weakening_needed,
    field_weakening_on,
    rated_torque_voltage_V,
)
from imdrive.config.machine import machine_presets, rated_point
from imdrive.config.presets import preset_names
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning


def _at(machine: str, speed_pu: float, *extra: str) -> Scenario:
    """``sensorless`` with ``[machine]`` replaced, its speed reference at ``speed_pu``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        sc = Scenario.read("sensorless", [f'machine.preset="{machine}"'])
        n = speed_pu * rated_point(sc.machine).speed_rpm
        ramp = f"control.speed_ref_rpm={{initial=0, changes=[{{at=0.5, to={n}, over=1.0}}]}}"
        return sc.with_overrides([ramp, *extra])


@pytest.mark.parametrize("machine", machine_presets())
def test_voltage_is_the_field_oriented_steady_state(machine):
    # the closed form against the analysis layer's steady state (R1 i + j w_e psi_s)
    sc = _at(machine, 1.0)
    m, rp = sc.machine, rated_point(sc.machine)
    assert m.B_Nms == 0.0  # the analysis adds friction to the load; the library has none
    for speed_pu in (0.3, 1.0, 1.7):
        n = speed_pu * rp.speed_rpm
        op = foc_operating_point(m, n, rp.torque_Nm, 1.0, m.rated_flux_Wb, False)
        assert rated_torque_voltage_V(sc, n) == pytest.approx(op.V_s_peak_V, rel=1e-9)
        assert rated_torque_voltage_V(sc, -n) == rated_torque_voltage_V(sc, n)


def test_table_iv_rated_point_needs_the_rated_voltage():
    # at the circuit's own rated flux and speed the rated torque takes the nameplate's
    # 220 V line-to-line: its phase peak sqrt(2/3) 220 = 179.6 V, all of Vdc/sqrt 3
    sc = _at("paper-table-iv", 1.0)
    rp = rated_point(sc.machine)
    sc = sc.with_overrides([f"control.flux_ref_Wb={rp.psi_r_Wb}"])
    v = rated_torque_voltage_V(sc, rp.speed_rpm)
    assert v == pytest.approx(math.sqrt(2.0 / 3.0) * 220.0, rel=1e-6)
    assert v == pytest.approx(sc.inverter.v_max_V, rel=1e-6)


@pytest.mark.parametrize("machine", machine_presets())
def test_default_follows_the_speed_reference(machine):
    below, above = _at(machine, 0.8), _at(machine, 0.95)
    assert below.control.field_weakening is None and above.control.field_weakening is None
    assert not field_weakening_on(below)
    assert field_weakening_on(above)
    # where it switches: the rated torque's voltage crosses field_weakening_voltage
    for sc in (below, above):
        top = sc.control.speed_ref_rpm.peak
        use = rated_torque_voltage_V(sc, top) / sc.inverter.v_max_V
        assert (use > sc.control.field_weakening_voltage) == field_weakening_on(sc)
    # reversing: the magnitude decides
    n = -0.95 * rated_point(above.machine).speed_rpm
    rev = above.with_overrides(
        [f"control.speed_ref_rpm={{initial=0, changes=[{{at=0.5, to={n}, over=1.0}}]}}"]
    )
    assert field_weakening_on(rev)


def test_set_value_wins_and_margin_keeps_it_off():
    sc = _at("krause-500hp", 1.0)
    assert field_weakening_on(sc)
    assert not field_weakening_on(sc.with_overrides(["control.field_weakening=false"]))
    assert field_weakening_on(_at("krause-500hp", 0.1, "control.field_weakening=true"))
    # a DC link with 25 % margin reaches the rated torque's voltage at the rated speed
    vdc = 1.25 * math.sqrt(2.0) * sc.machine.rated_voltage_V
    assert not field_weakening_needed(sc.with_overrides([f"inverter.Vdc_V={vdc}"]))
    # an open-loop drive has no field weakening to switch on
    assert not field_weakening_needed(sc.with_overrides(['drive.mode="open-loop"']))


def test_paper_presets_keep_it_off():
    # the paper's drives run at 1000 and 150 rpm, 0.58 and 0.09 of Table IV's rated speed;
    # the injection presets set it
    for name in preset_names():
        sc = Scenario.read(name)
        if sc.drive.mode != "vector":
            continue
        if sc.control.field_weakening is None:
            assert not field_weakening_on(sc), name
        else:
            assert field_weakening_on(sc) == sc.control.field_weakening, name


def test_show_all_says_what_the_default_is_here():
    # `imdrive show --all` (Scenario.to_toml): the unset setting's comment names its value in
    # this scenario, and the text still reads back to the same scenario (comments only)
    for speed_pu, here in ((0.95, "true"), (0.5, "false")):
        sc = _at("krause-500hp", speed_pu)
        text = sc.to_toml()
        assert f"# field_weakening is unset (its documented default applies: {here} here)" in text
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConfigWarning)
            again = Scenario.from_toml(text)
        assert again.to_dict() == sc.to_dict()
    open_loop = Scenario.read("free-acceleration").to_toml()
    assert "# field_weakening is unset (its documented default applies)\n" in open_loop
