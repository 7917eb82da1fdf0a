"""The keys of the R2 law not selected: a fuzzy-law key set under ``step_law = "kalman"``, or a
``[kalman]`` key under a fuzzy law, is accepted with a warning that says it has no effect
(config/checks.py ``law_keys_unread``); the presets as they stand warn nothing."""

from __future__ import annotations

import warnings

import pytest

from imdrive import Scenario
from imdrive.errors import ConfigError, ConfigWarning


def _warnings(preset, *overrides):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        Scenario.read(preset, list(overrides))
    return [str(w.message) for w in rec if issubclass(w.category, ConfigWarning)]


@pytest.mark.parametrize("key", ["gain_E_pu=400", "G_CR_pu=0.02", 'table="rules"'])
def test_a_fuzzy_key_under_the_kalman_law_says_it_has_no_effect(key):
    got = [w for w in _warnings("injection-robust", f"compensator.{key}") if "no effect" in w]
    assert len(got) == 1 and got[0].startswith(f"compensator.{key.split('=')[0]}:")
    assert "[kalman]" in got[0]


def test_a_kalman_key_under_a_fuzzy_law_says_it_has_no_effect():
    got = [w for w in _warnings("paper-fig5", "kalman.noise_pu=0.01") if "no effect" in w]
    assert got == ['kalman.noise_pu: has no effect: compensator.step_law is "table", not "kalman"']


@pytest.mark.parametrize("preset", ["injection-robust", "injection-fig5", "paper-fig5"])
def test_the_presets_warn_nothing_of_the_kind(preset):
    assert not [w for w in _warnings(preset) if "no effect" in w]


@pytest.mark.parametrize(("key", "value"), [("noise_pu", 0.0), ("drift_pu", -1.0)])
def test_the_kalman_settings_are_checked(key, value):
    with pytest.raises(ConfigError, match=rf"^kalman\.{key}: "):
        Scenario.read("injection-robust", [f"kalman.{key}={value}"])


@pytest.mark.parametrize(
    "key", ["fine_gain=1.0", "drift_gain=0.3", "overshoot_damping=false", "drift_max_ohm=0.1"]
)
def test_the_adaptive_laws_keys_are_accepted_with_a_deprecation_that_says_why(key):
    name = key.split("=")[0]
    got = [w for w in _warnings("injection-robust", f"compensator.{key}") if "deprecated" in w]
    assert len(got) == 1 and got[0].startswith(f"compensator.{name}: deprecated, no longer has")
    assert "Kalman" in got[0]


def test_the_adaptive_law_runs_as_the_kalman_law_with_a_warning():
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        sc = Scenario.read("injection-robust", ['compensator.step_law="adaptive"'])
    assert sc.compensator.step_law == "kalman"
    assert any("'adaptive' is deprecated and runs as 'kalman'" in str(w.message) for w in rec)


def test_a_deprecated_key_in_a_file_is_dropped_not_refused(tmp_path):
    f = tmp_path / "old.toml"
    f.write_text("[drive]\nmode = 'vector'\n[compensator]\nenabled = true\nfine_gain = 2.5\n")
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always")
        sc = Scenario.read(str(f))
    assert not hasattr(sc.compensator, "fine_gain")
