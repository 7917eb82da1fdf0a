"""The nameplate-only method of Lee, Frank, Sen et al.: its circuit meets the power balances it
is built from, and its inputs are checked."""

from __future__ import annotations

import math

import pytest

from imdrive.analysis.nameplate_lee import (
    NEMA_CODE_LETTERS,
    code_letter_kva_per_hp,
    code_letter_of,
    lee_circuit,
    locked_rotor_current_A,
    stray_loss_fraction,
)
from imdrive.errors import ConfigError

# a 2.2 kW, 400 V, 50 Hz, 4-pole plate: 1436 rpm, cos phi 0.79, eta 0.82, code letter G
PLATE = dict(power_W=2200.0, voltage_V=400.0, slip=1 - 1436 / 1500, efficiency=0.82)


def _circuit_powers(c, V_ph, s):
    """Input P, Q and air-gap power of the full circuit (core-loss branch included), three
    phases, and the locked-rotor current with the magnetising branch open."""
    Zm = 1 / (1 / c.RC + 1 / (1j * c.XM))
    Z2 = c.R2 / s + 1j * c.X2
    Z = c.R1 + 1j * c.X1 + Zm * Z2 / (Zm + Z2)
    I1 = V_ph / Z
    E = V_ph - (c.R1 + 1j * c.X1) * I1
    I2 = E / Z2
    S = 3 * V_ph * I1.conjugate()
    return S.real, S.imag, 3 * abs(I2) ** 2 * c.R2 / s, 3 * abs(E) ** 2 / c.RC


def test_circuit_meets_the_power_balances_of_the_method():
    P, V = PLATE["power_W"], PLATE["voltage_V"]
    I_lr = locked_rotor_current_A("G", P, V)
    c = lee_circuit(**PLATE, power_factor=0.79, locked_rotor_current_A=I_lr)
    s, V_ph = PLATE["slip"], V / math.sqrt(3)
    P_in, Q_in, P_ag, P_core = _circuit_powers(c, V_ph, s)
    L = c.losses_W
    assert P_in == pytest.approx(P / 0.82, rel=1e-9)
    assert Q_in == pytest.approx(P_in * math.tan(math.acos(0.79)), rel=1e-9)
    assert P_ag == pytest.approx(L["P_ag"], rel=1e-9)
    assert P_core == pytest.approx(L["P_core"], rel=1e-9)
    # the loss split: 12 % core, 14 % mechanical of the loss, 1.8 % stray of P (below 90 kW)
    loss = P / 0.82 - P
    assert L["P_core"] == pytest.approx(0.12 * loss) and L["P_mech"] == pytest.approx(0.14 * loss)
    assert L["P_stray"] == pytest.approx(0.018 * P)
    assert L["P_ag"] * (1 - s) == pytest.approx(P + L["P_mech"] + L["P_stray"], rel=1e-12)
    total = L["P_scl"] + L["P_rcl"] + L["P_core"] + L["P_mech"] + L["P_stray"]
    assert total == pytest.approx(loss, rel=1e-12)
    # the leakage: locked rotor with the magnetising branch open, X1 = X2 (design A split)
    assert abs(c.R1 + c.R2 + 1j * (c.X1 + c.X2)) == pytest.approx(V_ph / I_lr, rel=1e-9)
    assert c.X1 == pytest.approx(c.X2, rel=1e-12)
    assert c.iterations < 30


def test_design_letter_splits_the_leakage():
    I_lr = locked_rotor_current_A("G", 2200, 400)
    c = lee_circuit(**PLATE, power_factor=0.79, locked_rotor_current_A=I_lr, leakage_split=0.3)
    assert c.X1 / (c.X1 + c.X2) == pytest.approx(0.3, rel=1e-12)


def test_code_letters_and_stray_loss_by_rating():
    for letter, (lo, hi) in NEMA_CODE_LETTERS.items():
        kva = code_letter_kva_per_hp(letter)
        assert lo <= kva <= hi
        assert code_letter_of(kva if kva < hi else kva - 1e-9) == letter
    assert code_letter_kva_per_hp("G") == pytest.approx(5.95)
    # 10 hp at 460 V, code G: 59.5 kVA
    assert locked_rotor_current_A("G", 7460, 460) == pytest.approx(59.5e3 / (math.sqrt(3) * 460))
    assert [stray_loss_fraction(p) for p in (90e3, 91e3, 375e3, 1850e3, 2e6)] == [
        0.018,
        0.015,
        0.015,
        0.012,
        0.009,
    ]
    with pytest.raises(ConfigError) as err:
        code_letter_kva_per_hp("I")
    assert err.value.field == "code_letter"


@pytest.mark.parametrize(
    "changes, field",
    [
        (dict(efficiency=0.97), "efficiency"),  # the assumed losses leave no stator copper loss
        (dict(locked_rotor_current_A=1000.0), "locked_rotor_current"),  # V/I_LR below R1 + R2
        (dict(core_loss_fraction=1.2), "core_loss_fraction"),
    ],
)
def test_data_the_method_cannot_meet_are_refused(changes, field):
    args = dict(**PLATE, power_factor=0.79, locked_rotor_current_A=25.0) | changes
    with pytest.raises(ConfigError) as err:
        lee_circuit(**args)
    assert err.value.field == field
