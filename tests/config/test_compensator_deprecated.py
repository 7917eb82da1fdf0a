"""R2-tracking settings replaced by a rule in round 8 (issue 38; config/compensator_deprecated.py).

Each is accepted with a warning that says its rule and has no effect; a value that asks for
what the rule does (a scenario written out in full by an earlier release) warns nothing. The
presets' kernel records are the same with and without the key.
"""

from __future__ import annotations

import math
import warnings

import pytest

from imdrive.config.injection_backoff import backoff_band
from imdrive.config.scenario import Scenario
from imdrive.run.build import build_arrays


def _read(preset, *overrides):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sc = Scenario.read(preset, list(overrides))
    return sc, [str(w.message) for w in caught]


def _comp(sc) -> bytes:
    return build_arrays(sc).params.comp.tobytes()


@pytest.mark.parametrize(
    ("preset", "asks", "other"),
    [("paper-fig5", "e_d0", "demodulated"), ("injection-fig5", "demodulated", "e_d0")],
)
def test_the_input_is_demodulated_exactly_with_the_injection(preset, asks, other):
    plain, notes = _read(preset)
    assert notes == []
    record = build_arrays(plain).params.comp[0]
    assert record["demodulated"] == (preset == "injection-fig5")
    # the value the rule gives: dropped without a word
    same, notes = _read(preset, f'compensator.input="{asks}"')
    assert notes == [] and _comp(same) == _comp(plain)
    # the other one: a warning that says the rule, and no effect
    given, notes = _read(preset, f'compensator.input="{other}"')
    (note,) = [n for n in notes if n.startswith("compensator.input")]
    assert "no longer has any effect" in note
    assert "exactly when the injection runs" in note
    assert _comp(given) == _comp(plain)


def test_the_back_off_band_is_the_old_defaults_to_the_bit():
    assert backoff_band(0.88, 0.9) == (0.92, 0.98)  # the injection presets' band
    assert backoff_band(None, 0.9) == (0.85, 0.95)  # the old defaults
    record = build_arrays(_read("injection-robust")[0]).params.comp[0]
    assert (record["inj_v_lo"], record["inj_v_hi"], record["inj_v_peak"]) == (0.92, 0.98, 0.88)


@pytest.mark.parametrize(
    ("overrides", "band"),
    [((), (0.92, 0.98)), (("no estimation headroom",), (0.85, 0.95))],
)
def test_the_back_off_band_follows_the_voltage_the_field_weakening_holds(overrides, band):
    def read(*more):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sc = Scenario.read("injection-robust")
            if overrides:  # the estimation headroom off (unset)
                sc = sc.with_overrides({"injection.headroom_voltage": None})
            sc = sc.with_overrides(list(more)) if more else sc
        return sc, [str(w.message) for w in caught]

    plain, notes = read()
    assert notes == []
    lo, hi = band
    same, notes = read(f"injection.headroom_from={lo}", f"injection.headroom_to={hi}")
    assert notes == [] and _comp(same) == _comp(plain)
    given, notes = read(f"injection.headroom_from={lo - 0.02}", f"injection.headroom_to={hi}")
    (note,) = notes
    assert note.startswith("injection.headroom_from: deprecated, no longer has any effect")
    assert "follows the voltage the field weakening holds" in note
    assert _comp(given) == _comp(plain)
    given, notes = read(f"injection.headroom_to={hi + 0.01}")
    (note,) = notes
    assert note.startswith("injection.headroom_to:") and "headroom_voltage" in note
    assert _comp(given) == _comp(plain)


@pytest.mark.parametrize(
    ("preset", "steps"), [("paper-fig5", 100), ("injection-fig5", 5000), ("injection-robust", 5000)]
)
def test_the_window_is_one_injection_period_or_10_ms(preset, steps):
    plain, notes = _read(preset)
    assert notes == [] and build_arrays(plain).params.comp[0]["n"] == steps  # Ts = 100 us
    if preset == "paper-fig5":  # the paper presets stated the rule's 10 ms: no word
        same, notes = _read(preset, "compensator.period_s=0.01")
        assert notes == [] and _comp(same) == _comp(plain)
    given, notes = _read(preset, "compensator.period_s=1.0")
    (note,) = notes
    assert note.startswith("compensator.period_s: deprecated, no longer has any effect")
    assert "one injection period" in note and "10 ms" in note
    assert _comp(given) == _comp(plain)


def test_the_slip_decoupling_fades_in_from_0_3_of_the_rated_frequency():
    plain, _ = _read("injection-robust")
    f_rated = plain.machine.rated_frequency_Hz
    assert build_arrays(plain).params.comp[0]["cpl_wmin"] == 2 * math.pi * f_rated * 0.3
    same, notes = _read("injection-robust", "injection.decouple_slip_fmin_pu=0.3")
    assert notes == [] and _comp(same) == _comp(plain)
    given, notes = _read("injection-robust", "injection.decouple_slip_fmin_pu=0.15")
    (note,) = notes
    assert note.startswith("injection.decouple_slip_fmin_pu: deprecated, no longer has any")
    assert "0.3 of the rated stator frequency" in note
    assert _comp(given) == _comp(plain)


def test_the_kalman_laws_prior_is_the_rotors_resistance_swing_over_its_temperature_rise():
    plain, _ = _read("injection-robust")
    comp = plain.compensator
    p0 = build_arrays(plain).params.comp[0]["kf_p0"]
    assert p0 == comp.thermal_alpha_per_K * comp.thermal_rise_K  # 0.00393 x 80 K
    assert 0.31 < p0 < 0.32
    # a hotter class moves it: 105 K (class F) -> 0.41
    hot, _ = _read("injection-robust", "compensator.thermal_rise_K=105")
    assert build_arrays(hot).params.comp[0]["kf_p0"] == pytest.approx(0.00393 * 105)
    # the value the rule gives warns nothing; any other, the old default 0.3 included (the
    # prior it states is no longer the one used), says why
    same, notes = _read("injection-robust", f"kalman.prior_pu={0.00393 * 80.0!r}")
    assert notes == [] and _comp(same) == _comp(plain)
    for old in (0.3, 0.1):
        given, notes = _read("injection-robust", f"kalman.prior_pu={old}")
        (note,) = notes
        assert note.startswith("kalman.prior_pu: deprecated, no longer has any effect")
        assert "thermal_alpha_per_K x thermal_rise_K" in note
        assert _comp(given) == _comp(plain)
