"""R2-tracking settings replaced by a rule in round 8 (issue 38; config/compensator_deprecated.py).

Each is accepted with a warning that says its rule and has no effect; a value that asks for
what the rule does (a scenario written out in full by an earlier release) warns nothing. The
presets' kernel records are the same with and without the key.
"""

from __future__ import annotations

import warnings

import pytest

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
