"""Replacing ``[machine]`` under settings stated for the machine underneath is never silent
(config/pairs.py ``set_layer``): one warning names the absolute settings that stay as given
(with the per-unit twins that would follow the machine) and the controller-model tables
commissioned on the old machine.
"""

from __future__ import annotations

import warnings

import pytest

from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning


def _machine_warnings(preset: str, overrides: list[str]) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        Scenario.read(preset, overrides)
    return [
        str(w.message)
        for w in caught
        if issubclass(w.category, ConfigWarning) and str(w.message).startswith("machine:")
    ]


def test_absolute_settings_of_a_paper_preset_are_named():
    (msg,) = _machine_warnings("paper-fig5", ['machine.preset="krause-50hp"'])
    assert "krause-50hp replaces paper-table-iv" in msg
    assert "estimator.R2_ohm = 0.9792" in msg and "estimator.R2_ratio" in msg
    # its clamps are stated per-unit of R2_hat(0) since round 7, its gains are the defaults:
    # they follow the machine, and are not named
    assert "compensator." not in msg


ABSOLUTE = """
[machine]
preset = "paper-table-iv"
[drive]
mode = "vector"
[control]
speed_ref_rpm = { initial = 0, changes = [{ at = 0.5, to = 1000, over = 1.0 }] }
[load]
torque_Nm = { initial = 0, changes = [{ at = 2.0, to = 12 }] }
[estimator]
R2_ohm = 0.9792
[injection]
amplitude_A = 0.5
frequency_Hz = 2.0
[compensator]
enabled = true
input = "demodulated"
gain_E_per_Wb = 1000.0
G_CR_ohm = 0.02
R2_min_ohm = 0.408
R2_max_ohm = 1.224
"""


def test_many_settings_are_counted_not_dropped(tmp_path):
    path = tmp_path / "absolute.toml"
    path.write_text(ABSOLUTE)  # a user's file of before round 7: every key absolute
    (msg,) = _machine_warnings(str(path), ['machine.preset="aalto-2.2kw"'])
    # 9 absolute settings are stated: the speed and load profiles (rpm, N m), the
    # compensator's clamps, table gain and step, the estimator's R2, the injection's amplitude
    # and frequency; six are shown, the rest counted
    assert msg.count(" = ") == 6 and "and 3 more" in msg
    assert "control.speed_ref_rpm = " in msg and "load.torque_pu" in msg
    (msg,) = _machine_warnings("injection-fig5", ['machine.preset="aalto-2.2kw"'])
    # the profiles, R2_hat(0) and the online R1 law's rate
    assert msg.count(" = ") == 4 and "more" not in msg and "mras.R1_rate_per_s" in msg


def test_a_key_set_in_the_same_layer_is_not_stale():
    (msg,) = _machine_warnings(
        "paper-fig5", ['machine.preset="krause-50hp"', "estimator.R2_ratio=1.2"]
    )
    assert "estimator.R2_ohm" not in msg
    assert "control.speed_ref_rpm" in msg


def _measured_tables(tmp_path) -> str:
    """sensorless-realistic with its tables stated (a commissioning run's, ``ideal = false``)."""
    from imdrive.analysis.commissioning import ideal_commissioning, section_toml
    from imdrive.config.presets import scenario_text

    tables = section_toml(ideal_commissioning(Scenario.read("sensorless-realistic")))
    text = scenario_text("sensorless-realistic")
    assert "[controller_model]\nideal = true\n" in text
    path = tmp_path / "measured.toml"
    path.write_text(text.replace("[controller_model]\nideal = true\n", tables))
    return str(path)


def test_commissioned_tables_are_named(tmp_path):
    (msg,) = _machine_warnings(_measured_tables(tmp_path), ['machine.preset="krause-3hp"'])
    assert "controller_model tables" in msg and "magnetising_Lm_H" in msg
    assert "imdrive commission" in msg
    # its sensor range and sign band are derived now: not among the stale settings
    assert "adc_range_A" not in msg and "sign_band_A" not in msg


@pytest.mark.parametrize(
    ("preset", "overrides"),
    [
        ("injection-robust", ['machine.preset="krause-500hp"']),  # every such value per-unit
        ("sensorless", ['machine.preset="geyer-3.3kv"']),
        ("paper-fig5", ['machine.preset="paper-table-iv"']),  # the same machine again
        ("paper-fig5", ["machine.R2_ohm=0.9"]),  # the plant's parameter, not another machine
    ],
)
def test_silent_where_nothing_stays_tuned_for_another_machine(preset, overrides):
    assert _machine_warnings(preset, overrides) == []


def test_with_overrides_and_a_sweep_axis_warn_too():
    sc = Scenario.read("injection-fig6")
    with pytest.warns(ConfigWarning, match="krause-3hp replaces paper-table-iv"):
        sc.with_overrides(['machine.preset="krause-3hp"'])


@pytest.mark.parametrize("preset", ["sensorless", "injection-robust", "sensorless-realistic"])
def test_a_scenario_written_out_in_full_is_not_stale(preset, tmp_path):
    # with_overrides on a read scenario layers on its full dictionary: its defaults (the
    # controller model's mode keys, empty tables, per-unit settings) were stated for no machine
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        Scenario.read(preset).with_overrides(['machine.preset="krause-3hp"'])
    assert not [w for w in caught if str(w.message).startswith("machine:")]
    # a commissioned table written out in full still is
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        Scenario.read(_measured_tables(tmp_path)).with_overrides(['machine.preset="krause-3hp"'])
    assert [w for w in caught if "controller_model tables" in str(w.message)]
