"""R2-tracking settings replaced by a rule in round 7 (issue 38): ``compensator.average`` (the
decision window's mean, always) and ``injection.headroom`` (on exactly with the field
weakening). Each is accepted with a warning that says the rule, and has no effect; the
measurements behind the rules are in their deprecation notes (config/compensator.py).
"""

from __future__ import annotations

import warnings

import pytest

from imdrive.config.field_weakening import field_weakening_on
from imdrive.config.injection_backoff import backoff_band
from imdrive.config.scenario import Scenario
from imdrive.run.build import build_arrays


def _read(preset, *overrides):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sc = Scenario.read(preset, list(overrides))
    return sc, [str(w.message) for w in caught]


@pytest.mark.parametrize("preset", ["paper-fig5", "injection-fig5-realistic"])
def test_the_compensators_input_is_always_the_windows_mean(preset):
    sc, notes = _read(preset, "compensator.average=false")
    (note,) = [n for n in notes if n.startswith("compensator.average")]
    assert "no longer has any effect" in note and "mean over the decision window" in note
    assert build_arrays(sc).params.comp[0]["average"]  # the mean, as without the key
    assert (
        build_arrays(sc).params.comp.tobytes()
        == build_arrays(_read(preset)[0]).params.comp.tobytes()
    )


NO_FIELD_WEAKENING = {"control.field_weakening": False, "injection.headroom_voltage": None}


@pytest.mark.parametrize(
    ("overrides", "backs_off"),
    [
        ({}, True),  # injection-robust: field weakening on
        ({"injection.headroom": False}, True),  # the key is gone: the rule decides
        (NO_FIELD_WEAKENING, False),
        (NO_FIELD_WEAKENING | {"injection.headroom": True}, False),
    ],
)
def test_the_injection_backs_off_exactly_with_the_field_weakening(overrides, backs_off):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = Scenario.read("injection-robust").with_overrides(overrides)
    comp = build_arrays(sc).params.comp[0]
    assert field_weakening_on(sc) == backs_off
    assert (comp["inj_v_hi"] > 0.0) == backs_off
    if backs_off:
        assert (comp["inj_v_lo"], comp["inj_v_hi"]) == backoff_band(
            sc.injection.headroom_voltage, sc.control.field_weakening_voltage
        )


def test_the_headroom_key_warns_with_its_rule():
    _, notes = _read("injection-robust", "injection.headroom=false")
    (note,) = [n for n in notes if n.startswith("injection.headroom:")]
    assert "exactly when the field weakening is on" in note


@pytest.mark.parametrize("preset", ["paper-fig5", "injection-fig5-realistic"])
def test_the_change_of_e_is_scaled_as_e(preset):
    """The paper's Tables I and II quantise E and DE on one set of micro-weber thresholds:
    one gain, ``gain_E_pu`` (the paper's 1e6 /Wb, the realistic presets' 1000 /Wb)."""
    sc, _ = _read(preset)
    comp = build_arrays(sc).params.comp[0]
    assert comp["G_DE"] == comp["G_E"] == (1e6 if preset == "paper-fig5" else 1000.0)
    given, notes = _read(preset, "compensator.gain_DE_pu=1.0", "compensator.gain_E_pu=2.0")
    (note,) = [n for n in notes if n.startswith("compensator.gain_DE_pu")]
    assert "no longer has any effect" in note and "scaled as E" in note
    comp = build_arrays(given).params.comp[0]
    assert comp["G_DE"] == comp["G_E"] == 2.0 / sc.machine.rated_flux_Wb


def test_a_scenario_written_out_in_full_by_the_last_release_warns_only_where_it_differs():
    """A summary.json of 0.1 states every key: ``compensator.average = true`` and an
    ``injection.t_on_s`` equal to the compensator's ask for what the rules do."""
    old = {
        "drive": {"mode": "vector"},
        "compensator": {"enabled": True, "t_on_s": 4.0, "average": True},
        "injection": {"t_on_s": 4.0, "amplitude_pu": 0.075},
    }
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Scenario.from_dict(old)
    changed = {**old, "injection": {"t_on_s": 2.0, "amplitude_pu": 0.075}}
    with pytest.warns(Warning, match="injection.t_on_s: deprecated"):
        sc = Scenario.from_dict(changed)
    assert build_arrays(sc).params.comp[0]["inj_t_on"] == 4.0  # with the compensator


def test_an_unset_deprecated_key_of_a_summary_json_warns_nothing():
    """summary.json writes an unset key as null: ``gain_DE_pu``, ``injection.headroom``."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        Scenario.from_dict(
            {
                "drive": {"mode": "vector"},
                "compensator": {"gain_DE_pu": None, "gain_DE_per_Wb": None},
                "injection": {"headroom": None},
            }
        )
