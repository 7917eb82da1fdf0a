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


@pytest.mark.parametrize("key", ["fine_gain=1.0", "G_CR_pu=0.02", 'table="rules"'])
def test_a_fuzzy_key_under_the_kalman_law_says_it_has_no_effect(key):
    got = [w for w in _warnings("injection-robust", f"compensator.{key}") if "no effect" in w]
    assert len(got) == 1 and got[0].startswith(f"compensator.{key.split('=')[0]}:")
    assert "[kalman]" in got[0]


def test_a_kalman_key_under_a_fuzzy_law_says_it_has_no_effect():
    got = [w for w in _warnings("injection-fig5", "kalman.noise_pu=0.01") if "no effect" in w]
    assert got == [
        'kalman.noise_pu: has no effect: compensator.step_law is "adaptive", not "kalman"'
    ]


@pytest.mark.parametrize("preset", ["injection-robust", "injection-fig5", "paper-fig5"])
def test_the_presets_warn_nothing_of_the_kind(preset):
    assert not [w for w in _warnings(preset) if "no effect" in w]


@pytest.mark.parametrize(
    ("key", "value"), [("noise_pu", 0.0), ("drift_pu", -1.0), ("prior_pu", float("nan"))]
)
def test_the_kalman_settings_are_checked(key, value):
    with pytest.raises(ConfigError, match=rf"^kalman\.{key}: "):
        Scenario.read("injection-robust", [f"kalman.{key}={value}"])
