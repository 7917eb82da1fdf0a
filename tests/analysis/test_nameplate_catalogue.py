"""The catalogue method: every figure of a catalogue, R1 the stator's, the leakage from the
breakdown torque when given; its bad input and its deprecated predecessors."""

from __future__ import annotations

import math
import warnings

import pytest

from imdrive.analysis.nameplate import Nameplate, estimate_circuit
from imdrive.cli import main
from imdrive.errors import ConfigError, ConfigWarning
from imdrive.studies import nameplate_published as npub

W_60 = 2 * math.pi * 60

# the 22 kW, 400 V catalogue motor of issue 39 (T_bd/T_n 2.8, I_st/I_n 7.3)
MOTOR_22KW = dict(power_W=22e3, voltage_V=400, frequency_Hz=50, poles=4, speed_rpm=1470,
                  current_A=40.0, power_factor=0.84, efficiency=0.93)  # fmt: skip


def _catalogue(**kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the catalogue method is not deprecated
        return estimate_circuit(Nameplate(**(MOTOR_22KW | kw)), method="catalogue")


def test_published_figures_of_the_true_motors():
    """The true-motor model reproduces the figures the textbooks print (pvlib-style pins):
    Chapman Example 7-5, 18.88 A at power factor 0.833; Sen Example 5.4, 42.754 A at the
    book's slip 0.0333, 245.9 A and 431.68 N m at slip 0.1963 (the book's rounded Thevenin
    form: within 1 %)."""
    t = npub.true_motor("chapman-25hp")
    assert t["I1"] == pytest.approx(18.88, rel=1e-3)
    assert t["pf"] == pytest.approx(0.833, abs=1e-3)
    sen = npub.PUBLISHED["sen-5.4"]
    assert npub._operating_point(sen, 0.0333)["I1"] == pytest.approx(42.754, rel=1e-3)
    t = npub.true_motor("sen-5.4")
    assert t["I_st"] == pytest.approx(245.9, rel=0.01)
    T_e_max = t["T_bd"] + sen["P_rot_W"] / npub._operating_point(sen, t["slip"])["w_m"]
    assert T_e_max == pytest.approx(431.68, rel=0.01)


@pytest.mark.parametrize("leakage", ["breakdown", "starting"])
def test_published_circuit_comes_back_from_its_catalogue_and_losses(leakage):
    """Sen's Example 5.4 (X1 = X2, the design-A split): its nameplate, its breakdown torque
    (or starting current) and its losses give the circuit back element for element."""
    d = npub.PUBLISHED["sen-5.4"]
    plate, options = npub.catalogue("sen-5.4", "catalogue+losses")
    t = npub.true_motor("sen-5.4")
    if leakage == "breakdown":  # the plant's breakdown torque is the electromagnetic one
        w_n = npub._operating_point(d, t["slip"])["w_m"]
        changes = dict(breakdown_torque_ratio=(t["T_bd"] + d["P_rot_W"] / w_n) / t["T_n"])
    else:
        changes = dict(breakdown_torque_ratio=None)
    plate = Nameplate(**(plate.__dict__ | changes))
    m = estimate_circuit(plate, method="catalogue", **options).machine
    got = (m.R1_ohm, m.R2_ohm, m.Ll1_H * W_60, m.Ll2_H * W_60, m.M_H * W_60)
    assert got == pytest.approx((d["R1"], d["R2"], d["X1"], d["X2"], d["XM"]), rel=1e-6)


def test_leakage_from_the_breakdown_torque_not_the_starting_current():
    """With both figures the breakdown torque sets the leakage (met exactly), and the circuit's
    starting current is reported against the catalogue's; from the starting current alone the
    breakdown torque of this deep-bar motor comes out 40 % high (issue 39: lee gave +34 %)."""
    both = _catalogue(breakdown_torque_ratio=2.8, starting_current_ratio=7.3)
    T_n = 22e3 / (1470 * math.pi / 30)
    assert both.details["leakage_from"] == "breakdown torque"
    assert both.details["breakdown_torque_Nm"] == pytest.approx(2.8 * T_n, rel=1e-9)
    assert both.residuals["starting_current"] < -0.2  # a single cage starts with less
    only_st = _catalogue(starting_current_ratio=7.3)
    assert only_st.details["leakage_from"] == "starting current"
    assert only_st.details["starting_current_A"] == pytest.approx(7.3 * 40.0, rel=1e-9)
    assert only_st.details["breakdown_torque_Nm"] / T_n > 1.3 * 2.8


def test_R1_is_the_stators_not_a_lump_of_every_loss():
    """R1 = P_scl / (3 I^2) of the loss split, whatever sets the leakage; the deprecated fit
    puts every loss into R1 (issue 39: 2.5 times on this motor)."""
    cat = _catalogue(breakdown_torque_ratio=2.8, starting_current_ratio=7.3)
    d = cat.details
    I = d["P_in_W"] / (math.sqrt(3) * 400 * 0.84)
    assert cat.machine.R1_ohm == pytest.approx(d["P_scl_W"] / (3 * I**2), rel=1e-12)
    assert _catalogue(starting_current_ratio=7.3).machine.R1_ohm == cat.machine.R1_ohm
    with pytest.warns(DeprecationWarning, match="method='catalogue'"):
        fit = estimate_circuit(Nameplate(**MOTOR_22KW, breakdown_torque_ratio=2.8), method="fit")
    assert fit.machine.R1_ohm / cat.machine.R1_ohm > 2.0


def test_no_method_keeps_fit_with_a_deprecation_warning():
    plate = Nameplate(**MOTOR_22KW, breakdown_torque_ratio=2.8)
    with pytest.warns(DeprecationWarning, match="no method"):
        old = estimate_circuit(plate)
    assert old.method == "fit"


BD_PF = "breakdown_torque_ratio, power_factor"


@pytest.mark.parametrize(
    "changes, field",
    [
        (dict(breakdown_torque_ratio=0.9), "breakdown_torque_ratio"),  # below rated torque
        (dict(efficiency=1.05), "efficiency"),
        (dict(current_A=30.0), "current_A, power_factor"),  # sqrt 3 V I cos phi below P
        (dict(power_factor=0.97, breakdown_torque_ratio=1.3), BD_PF),
        (dict(power_factor=0.97, starting_current_ratio=3.0), "starting_current, power_factor"),
    ],
)
def test_contradictory_catalogue_is_refused_naming_the_fields(changes, field):
    with pytest.raises(ConfigError) as err:
        _catalogue(**changes)
    assert err.value.field == field and "\n" not in str(err.value)


@pytest.mark.parametrize(
    "flags, names",
    [
        ("--breakdown-ratio 0.9", "--breakdown-ratio"),
        ("--efficiency 1.05", "--efficiency"),
        ("--current 30", "--current, --pf"),
        ("--pf 0.97 --breakdown-ratio 1.3", "--breakdown-ratio, --pf"),
    ],
)
def test_contradictory_catalogue_exits_2_with_one_line(flags, names, capsys):
    args = "--power-kw 22 --voltage 400 --frequency 50 --poles 4 --speed 1470 --current 40 "
    args += "--pf 0.84 --efficiency 0.93 " + flags  # a repeated flag: the last one counts
    assert main(["machine-from-nameplate", *args.split()]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"imdrive: error: {names}: ") and "\n" not in err


def test_slip_outside_the_usual_range_warns_in_one_line(capsys):
    with pytest.warns(ConfigWarning) as rec:
        _catalogue_quiet_deprecations(speed_rpm=1499.0)
    assert [w.message.field for w in rec if isinstance(w.message, ConfigWarning)][0] == "speed_rpm"
    args = "--power-kw 22 --voltage 400 --frequency 50 --poles 4 --speed 1499 --current 40 "
    args += "--pf 0.84 --efficiency 0.93"
    assert main(["machine-from-nameplate", *args.split()]) == 0
    err = capsys.readouterr().err
    assert "imdrive: warning: --speed: rated slip 0.0667 % is outside the usual 0.2-10 %" in err


def _catalogue_quiet_deprecations(**kw):
    return estimate_circuit(Nameplate(**(MOTOR_22KW | kw)), method="catalogue")


def test_default_method_of_the_command_is_catalogue_and_lee_warns(capsys):
    args = "--power-kw 22 --voltage 400 --frequency 50 --poles 4 --speed 1470 --current 40 "
    args += "--pf 0.84 --efficiency 0.93 --breakdown-ratio 2.8 --starting-current-ratio 7.3"
    assert main(["machine-from-nameplate", *args.split()]) == 0
    out, err = capsys.readouterr()
    assert "method catalogue" in err and "leakage from the breakdown torque" in err
    assert "method catalogue" in out and "warning" not in err
    args = args.replace("--breakdown-ratio 2.8 ", "") + " --method lee"
    assert main(["machine-from-nameplate", *args.split()]) == 0
    err = capsys.readouterr().err
    assert "imdrive: warning: --method: lee is deprecated" in err and "--method catalogue" in err
