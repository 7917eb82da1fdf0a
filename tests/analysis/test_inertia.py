"""Default rotor inertia from the machine's size (imdrive.analysis.inertia) and its wiring into
the nameplate estimate."""

from __future__ import annotations

import math
import warnings

import pytest

from imdrive.analysis import inertia
from imdrive.analysis.nameplate import Nameplate, estimate_circuit
from imdrive.cli import main
from imdrive.errors import ConfigWarning

#: the 22 kW, 4-pole motor of issue 39
MOTOR_22KW = dict(
    power_W=22000.0, voltage_V=400.0, frequency_Hz=50.0, poles=4, speed_rpm=1470.0,
    current_A=40.0, power_factor=0.84, efficiency=0.93, breakdown_torque_ratio=2.8,
)  # fmt: skip


def _estimate(**kw):
    return estimate_circuit(Nameplate(**(MOTOR_22KW | kw)), method="catalogue")


def test_the_law_is_a_power_of_the_rated_torque():
    T_n = 22000.0 / (1470.0 * math.pi / 30.0)
    J = inertia.INERTIA_COEFFICIENT_KGM2 * T_n**inertia.INERTIA_EXPONENT
    assert inertia.rotor_inertia_kgm2(22000.0, 1470.0) == pytest.approx(J, rel=1e-12)
    # the same power at half the speed (twice the poles) is twice the torque
    ratio = inertia.rotor_inertia_kgm2(22000.0, 735.0) / inertia.rotor_inertia_kgm2(22000.0, 1470)
    assert ratio == pytest.approx(2.0**inertia.INERTIA_EXPONENT, rel=1e-12)


def test_small_motors_get_far_less_than_the_former_half_second():
    """The former default (H = 0.5 s) gave a 0.75 kW 2-pole motor 8 times its catalogue J
    (SOGA MT3 80 MA/2: 0.0010 kg m^2); the size law is within 1.5 times of it."""
    J = inertia.rotor_inertia_kgm2(750.0, 2900.0)
    H_former = 0.5
    J_former = 2.0 * H_former * 750.0 / (2900.0 * math.pi / 30.0) ** 2
    assert J_former / 0.0010 > 7.0
    assert 1 / 1.5 <= J / 0.0010 <= 1.5
    assert inertia.inertia_constant_s(J, 750.0, 2900.0) < 0.1


def test_a_plate_without_J_gets_the_size_law_and_says_so():
    fit = _estimate()
    assert fit.machine.J_kgm2 == pytest.approx(inertia.rotor_inertia_kgm2(22000.0, 1470.0))
    said = [a for a in fit.assumed if a.startswith("J = ")]
    assert len(said) == 1 and "rotor of this size" in said[0]
    assert "imdrive.analysis.inertia" in said[0]


def test_a_plate_with_J_keeps_it_and_assumes_nothing_about_it():
    fit = _estimate(J_kgm2=0.2)
    assert fit.machine.J_kgm2 == 0.2
    assert not any(a.startswith("J") for a in fit.assumed)


@pytest.mark.parametrize("factor", [1 / 3.9, 1.0, 3.9])
def test_a_J_of_the_size_class_does_not_warn(factor):
    J = factor * inertia.rotor_inertia_kgm2(22000.0, 1470.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConfigWarning)
        _estimate(J_kgm2=J)


@pytest.mark.parametrize("factor", [1e-4, 1 / 4.1, 4.1, 100.0])
def test_a_J_far_from_the_size_class_warns_in_one_line(factor):
    J = factor * inertia.rotor_inertia_kgm2(22000.0, 1470.0)
    with pytest.warns(ConfigWarning) as rec:
        fit = _estimate(J_kgm2=J)
    assert fit.machine.J_kgm2 == J  # a warning, not an error: the value is kept
    msgs = [w.message for w in rec if isinstance(w.message, ConfigWarning)]
    assert [m.field for m in msgs] == ["J_kgm2"]
    assert "\n" not in msgs[0].rule and "times the" in msgs[0].rule


def test_the_command_names_the_flag_of_a_far_J(capsys):
    args = "--power-kw 22 --voltage 400 --frequency 50 --poles 4 --speed 1470 --current 40 "
    args += "--pf 0.84 --efficiency 0.93 --J 1550"  # kg cm^2 given as kg m^2
    assert main(["machine-from-nameplate", *args.split()]) == 0
    err = capsys.readouterr().err
    lines = [x for x in err.splitlines() if "warning" in x]
    assert len(lines) == 1 and lines[0].startswith("imdrive: warning: --J: 1550 kg m^2")


def test_the_former_constant_is_still_importable_with_a_deprecation():
    with pytest.warns(DeprecationWarning, match="rotor_inertia_kgm2"):
        from imdrive.analysis.nameplate import DEFAULT_INERTIA_CONSTANT_S
    assert DEFAULT_INERTIA_CONSTANT_S == 0.5
    with pytest.raises(AttributeError):
        import imdrive.analysis.nameplate as nameplate

        nameplate.NO_SUCH_NAME  # noqa: B018
