"""The injection presets' first-release tuning, for the tests that reproduce a finding with it.

The injection presets (``injection-fig5``, ``-fig6``, their ``-150rpm`` twins) now carry the
recommended mechanisms (the model-based R2 law, three frequencies, R1 estimation, field weakening
with the estimation headroom, the rotor thermal model, the slip decoupling of the detection,
the MRAS's period-mean current).
A test that shows what a mechanism fixes starts from the tuning the presets had before:
:data:`FIRST_RELEASE` restores it, and ``tests/drive/test_first_release_tuning.py`` checks
that it does, bit for bit, against the fingerprints the presets had then
(``first_release_baseline.json``).
"""

from __future__ import annotations

from imdrive.config.scenario import Scenario

#: Overrides that turn an injection preset back into its first-release tuning.
FIRST_RELEASE = {
    "control.field_weakening": False,
    "mras.R1_standstill": False,
    "mras.R1_rate_per_s": 0.0,
    "injection.headroom_voltage": None,
    "compensator.step_law": "table",  # the paper's table with the first release's scaling
    "compensator.table": "paper",
    "compensator.gain_E_pu": 463.1158419669872,  # 1000 /Wb on Table IV (E and DE), to the bit
    # the step and the clamps in ohm as the first release had them, whatever R2_hat(0) a test
    # sets (deprecated spellings: their per-unit twins are of R2_hat(0))
    "compensator.G_CR_ohm": 0.02,
    "compensator.R2_min_ohm": 0.408,
    "compensator.R2_max_ohm": 1.224,
    # half the 2 Hz injection, the 1 Hz the first release had as its default (its two-frequency
    # schedule is the harmonics' schedule now, which a band of half the frequency makes the
    # same away from 3 Hz)
    "compensator.gate_band_pu": 0.5,
    "compensator.gate_voltage": 0.97,
    "compensator.thermal_model": False,
    "injection.decouple_slip": False,
    "mras.period_mean_current": False,
    "mras.regeneration_angle_deg": 0.0,  # Schauder's adaptation error
}


def first_release(name: str, overrides=()) -> Scenario:
    """Injection preset ``name`` in its first-release tuning, then ``overrides`` (strings
    ``"key=value"`` as for :meth:`Scenario.read`)."""
    sc = Scenario.read(name).with_overrides(FIRST_RELEASE)
    return sc.with_overrides(list(overrides)) if overrides else sc
