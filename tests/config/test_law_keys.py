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


def test_a_model_based_law_without_the_injection_says_r2_is_not_tracked():
    # the Kalman law's only measurement is the injected flux response: on the paper's drive
    # (no injection) it would leave R2_hat where it starts, 20 % off, with no word until the end
    got = _warnings("paper-fig5", 'compensator.step_law="kalman"')
    got = [w for w in got if "not tracked" in w]
    assert len(got) == 1 and got[0].startswith("compensator.step_law:")
    assert not [w for w in _warnings("injection-robust") if "not tracked" in w]


def test_the_package_s_laws_keys_under_a_plug_in_law_say_they_have_no_effect():
    from pathlib import Path

    module = Path(__file__).parents[1] / "data" / "own_r2_law.py"
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        Scenario.read(
            "injection-robust",
            [f'plugins.modules=["{module}"]', 'compensator.step_law="relax"']
            + ["compensator.G_CR_pu=0.01", "kalman.noise_pu=0.05"],
            allow_plugins=True,
        )
    got = sorted(str(w.message) for w in rec if "no effect" in str(w.message))
    assert [g.split(":")[0] for g in got] == ["compensator.G_CR_pu", "kalman.noise_pu"]
    assert 'step_law = "relax"' in got[0] and '"relax", not "kalman"' in got[1]
