"""The one resolver of scenario-dependent defaults (config/defaults.py): the drive's records,
``show --all`` / ``summary.json`` and docs/scenarios.md all take a derived setting from it.

Issue 39 ("one resolver of machine-dependent defaults"): before, ``run/blocks.py`` called seven
functions directly, ``config/resolved.py`` called them again for ``show --all`` and the docs'
texts were hand-written beside each setting.
"""

from __future__ import annotations

import warnings

import pytest

from imdrive.config.defaults import DERIVED, derived_defaults, in_effect
from imdrive.config.docs import _default, _derived_values
from imdrive.config.presets import preset_names
from imdrive.config.resolved import resolved_defaults
from imdrive.config.scenario import Scenario
from imdrive.config.schema import scenario_keys
from imdrive.errors import ConfigWarning
from imdrive.run.build import build_arrays

#: resolver key -> (record of DriveParams, field) that carries its value into the kernels
RECORD_FIELD = {
    "control.field_weakening": ("control", "fw"),
    "control.speed_gain_flux_scaling": ("control", "w_fw_sched"),
    "control.current_limit_A": ("control", "i_max"),
    "control.inverter_error_adaptation_per_s": ("control", "ie_rate"),
    "simulation.divergence_current_A": ("sim", "i_lim"),
    "inverter.sign_band_A": ("inverter", "i_band"),
    "sensor.adc_range_A": ("sensor", "adc_range"),
    "flux_injection.frequency_Hz": ("sim", "flux_inj_freq"),
    "plant.thermal.Rth1_K_per_W": ("plant", "Rth1"),
    "plant.thermal.Rth2_K_per_W": ("plant", "Rth2"),
    "compensator.G_CR_ohm": ("comp", "G_CR"),
    "compensator.R2_min_ohm": ("comp", "R2_min"),
    "compensator.gating": ("comp", "gate"),
    "compensator.R2_max_ohm": ("comp", "R2_max"),
    "compensator.gain_E_per_Wb": ("comp", "G_E"),
    "injection.frequency_Hz": ("comp", "inj_freq"),
}


#: ... the estimator's own, each on a drive running that estimator
ESTIMATOR_FIELD = {
    "afo": ("afo.R1_bandwidth_rad_s", "sensorless", 'control.speed_feedback="afo"'),
    "ekf": ("ekf.current_noise_A", "sensorless", 'control.speed_feedback="ekf"'),
}


def _read(name: str, *overrides: str) -> Scenario:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        return Scenario.read(name, list(overrides))


def test_every_entry_is_a_setting_whose_docs_default_is_its_rule():
    keys = {k.dotted: k for k in scenario_keys() if k.table is None}
    for key, entry in DERIVED.items():
        assert key in keys, key
        extra = keys[key].info.json_schema_extra or {}
        # the setting declares itself derived and holds no text of its own: docs/scenarios.md
        # prints the resolver's rule, written once
        assert extra.get("derived") is True and "default_doc" not in extra, key
        assert _default(keys[key], None) == "*derived*: " + entry.rule.format(**_derived_values())
    # and no setting declares itself derived without an entry here
    flagged = {k for k, v in keys.items() if (v.info.json_schema_extra or {}).get("derived")}
    assert flagged == set(DERIVED)


@pytest.mark.parametrize("preset", preset_names())
def test_the_drive_records_carry_the_resolved_values(preset):
    sc = _read(preset)
    params = build_arrays(sc).params
    checked = 0
    for key, (record, field) in RECORD_FIELD.items():
        if not DERIVED[key].applies(sc):
            continue
        got = params._asdict()[record][field][0]
        assert got == pytest.approx(float(in_effect(sc, key)), rel=1e-12), (preset, key)
        checked += 1
    if sc.drive.mode == "vector":
        assert checked >= 6, preset


@pytest.mark.parametrize("preset", ["sensorless", "injection-robust", "sensorless-realistic"])
def test_show_all_and_summary_list_what_the_drive_runs_with(preset):
    sc = _read(preset)
    listed = resolved_defaults(sc)
    assert listed == derived_defaults(sc)
    for key, value in listed.items():
        assert value == in_effect(sc, key), key
    assert "control.field_weakening" in listed
    assert "sensor.adc_range_A" in listed


def test_a_set_value_reaches_the_records_through_the_resolver():
    sc = _read("sensorless", "sensor.adc_range_A=37.5", "control.current_limit_A=21.0")
    assert in_effect(sc, "sensor.adc_range_A") == 37.5
    params = build_arrays(sc).params
    assert params.sensor["adc_range"][0] == 37.5
    assert params.control["i_max"][0] == 21.0


def test_the_unset_value_follows_the_machine():
    small = _read("sensorless")
    large = _read("sensorless", 'machine.preset="krause-500hp"')
    for key in ("sensor.adc_range_A", "inverter.sign_band_A", "control.current_limit_A"):
        # each scales with the rated peak current: a large machine's is larger
        assert in_effect(large, key) > 10 * in_effect(small, key), key


def test_an_unknown_key_is_refused():
    with pytest.raises(KeyError):
        in_effect(_read("sensorless"), "control.no_such_setting")


def test_summary_and_show_all_list_a_nested_setting_left_unset():
    from imdrive.config.resolved import unset_resolved_defaults

    sc = _read("sensorless", "plant.thermal.enabled=true", "sensor.adc_range_A=37.5")
    unset = unset_resolved_defaults(sc)
    # three levels deep, and only the unset ones (adc_range_A is set here)
    assert unset["plant.thermal.Rth2_K_per_W"] == in_effect(sc, "plant.thermal.Rth2_K_per_W")
    assert "sensor.adc_range_A" not in unset
    # show --all writes the value beside an unset setting of a table of its own
    shown = _read("sensorless").to_toml()
    value = in_effect(_read("sensorless"), "sensor.adc_range_A")
    assert f"adc_range_A is unset (its documented default applies: {value} here)" in shown


def test_the_speed_loop_and_the_divergence_bound_follow_the_resolver():
    import math

    sc = _read("sensorless", 'machine.preset="krause-50hp"')
    params = build_arrays(sc).params
    w_lim = in_effect(sc, "simulation.divergence_speed_rpm") * math.pi / 30.0
    assert params.sim["w_lim"][0] == pytest.approx(w_lim, rel=1e-12)
    # the speed gains: set to the resolver's value, the bandwidth gives the same gains
    bw = in_effect(sc, "control.speed_bandwidth_Hz")
    same = _read("sensorless", 'machine.preset="krause-50hp"', f"control.speed_bandwidth_Hz={bw!r}")
    other = build_arrays(same).params
    for field in ("kp_w", "ki_w"):
        assert params.control[field][0] == other.control[field][0], field


@pytest.mark.parametrize("name", sorted(ESTIMATOR_FIELD))
def test_an_estimator_registers_its_own_derived_settings(name):
    key, preset, choose = ESTIMATOR_FIELD[name]
    sc = _read(preset, choose)
    assert key in derived_defaults(sc)  # listed by show --all and summary.json
    assert key not in derived_defaults(_read(preset))  # not with another estimator
    large = _read(preset, choose, 'machine.preset="krause-500hp"')
    assert in_effect(large, key) != in_effect(sc, key)  # it follows the machine
