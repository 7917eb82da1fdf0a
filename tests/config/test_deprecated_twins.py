"""The absolute spellings of the R2-tracking's per-unit settings are deprecated twins (round 7,
issue 38): each still acts, with one warning naming its per-unit twin, and is listed apart in
docs/scenarios.md; the presets state the twins with values that give the old floats to the
last bit (or leave them to the default that is the old number on Table IV).
"""

from __future__ import annotations

import warnings

import pytest

from imdrive.config.perunit import resolve
from imdrive.config.scaled import flux_injection_frequency_Hz
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning

INJ = ["compensator.enabled=true"]  # the input is demodulated with the injection

#: key=value -> (its per-unit twin, how the resolved scenario reads it)
TWINS = {
    "compensator.gain_E_per_Wb=1234.5": ("compensator.gain_E_pu", lambda sc, r: r.gain_E),
    "compensator.G_CR_ohm=1234.5e-6": ("compensator.G_CR_pu", lambda sc, r: r.G_CR * 1e6),
    "compensator.R2_min_ohm=0.5": ("compensator.R2_min_ratio", lambda sc, r: r.R2_min),
    "compensator.R2_max_ohm=1.5": ("compensator.R2_max_ratio", lambda sc, r: r.R2_max),
    "injection.amplitude_A=0.5": ("injection.amplitude_pu", lambda sc, r: r.inj_amp),
    "injection.frequency_Hz=2.5": ("injection.frequency_pu", lambda sc, r: r.inj_f1),
    "flux_injection.frequency_Hz=2.5": (
        "flux_injection.frequency_pu",
        lambda sc, r: flux_injection_frequency_Hz(sc),
    ),
}


def _read(*overrides) -> tuple[Scenario, list[str]]:
    """The sensorless preset with the injection compensator (0.075 per-unit unless the
    overrides state the amplitude)."""
    amp = [] if any("amplitude" in o for o in overrides) else ["injection.amplitude_pu=0.075"]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sc = Scenario.read("sensorless", [*INJ, *amp, *overrides])
    return sc, [str(w.message) for w in caught if issubclass(w.category, ConfigWarning)]


@pytest.mark.parametrize("override", sorted(TWINS))
def test_a_deprecated_twin_warns_naming_its_twin_and_acts(override):
    key, value = override.split("=")
    twin, read = TWINS[override]
    sc, notes = _read(override)
    mine = [n for n in notes if n.startswith(f"{key}: deprecated")]
    assert mine == [
        f"{key}: deprecated, refused from imdrive 0.3: state it per-unit of the machine as {twin} "
        "(it still acts until then)"
    ]
    # it acts: the resolved value is the absolute one as given
    want = float(value) * (1e6 if key.endswith("G_CR_ohm") else 1.0)
    assert read(sc, resolve(sc)) == pytest.approx(want, rel=1e-12)


def test_the_old_default_of_the_amplitude_states_nothing():
    """A scenario written out in full by the last release carries ``amplitude_A = 0.0``."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sc = Scenario.from_dict({"drive": {"mode": "vector"}, "injection": {"amplitude_A": 0.0}})
    assert resolve(sc).inj_amp == 0.0
    _, notes = _read("injection.amplitude_A=0.25")
    assert any(n.startswith("injection.amplitude_A: deprecated") for n in notes)


#: what each preset stated in absolute units until round 7: (R2_min, R2_max, G_CR, gain_E,
#: gain_DE, amplitude A, frequency Hz); None: not stated
ABSOLUTE = {
    **{
        p: (0.408, 1.224, 0.001, 1e6, 1e6, None, None)
        for p in (
            "paper-fig5",
            "paper-fig5-150rpm",
            "paper-fig5-realistic",
            "paper-fig6",
            "paper-fig6-150rpm",
            "paper-fig6-realistic",
        )
    },
    **{
        p: (0.408, 1.224, None, None, None, 0.5, 2.0)
        for p in (
            "injection-fig5",
            "injection-fig5-150rpm",
            "injection-fig6",
            "injection-fig6-150rpm",
        )
    },
    **{
        p: (0.408, 1.224, 0.02, 1000.0, 1000.0, 0.5, 2.0)
        for p in ("injection-fig5-realistic", "injection-fig6-realistic")
    },
}


@pytest.mark.parametrize("preset", sorted(ABSOLUTE))
def test_the_presets_per_unit_values_give_the_old_floats_to_the_bit(preset):
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConfigWarning)  # no preset states a deprecated key
        sc = Scenario.read(preset)
    r = resolve(sc)
    got = (r.R2_min, r.R2_max, r.G_CR, r.gain_E, r.gain_DE, r.inj_amp, r.inj_f1)
    for name, g, want in zip(
        ("R2_min", "R2_max", "G_CR", "gain_E", "gain_DE", "inj_amp", "inj_f1"),
        got,
        ABSOLUTE[preset],
        strict=True,
    ):
        if want is not None:
            assert g == want, name  # exact: the preset baseline is bit for bit
