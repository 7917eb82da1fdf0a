"""Every preset gives bit for bit the results stored in tests/data/preset_baseline.json.

``tests/data/preset_baseline.json`` holds, per preset, the status, the number of periods, the
final value of every column, the energies, the compensation metrics and a SHA-256 of every
logged column. It was written by ``tests/data/make_preset_baseline.py`` from the first release
(commit 6816c96); regenerate it only for an intended change of numerics. It keeps the column
names of then: the fingerprint reads a renamed column (``R2_est_ohm`` -> ``R2_hat_ohm``) under
its new name and hashes it under the stored one.

The baseline logged every period unless the preset sets ``simulation.log_every``; since the
default became a decimation (about 1 kHz), a preset that does not set it is run with
``simulation.log_every = 1`` pinned, so the hashes still compare the same samples.
"""

import json
import tomllib
from pathlib import Path

import pytest
from data.make_preset_baseline import fingerprint

from imdrive.config.presets import preset_names, preset_text
from imdrive.config.scenario import Scenario
from imdrive.run.simulate import simulate

BASELINE = json.loads((Path(__file__).parents[1] / "data" / "preset_baseline.json").read_text())


def baseline_overrides(name: str) -> list[str]:
    """``simulation.log_every = 1`` when the preset leaves it to the default (see above)."""
    sim = tomllib.loads(preset_text(name)).get("simulation", {})
    return [] if "log_every" in sim else ["simulation.log_every=1"]


def test_baseline_pins_full_rate_logging_where_the_preset_is_silent():
    assert baseline_overrides("paper-fig5") == []  # sets log_every = 10 itself
    assert Scenario.read("paper-fig5", baseline_overrides("paper-fig5")).simulation.log_every == 10
    silent = Scenario.from_toml(
        "\n".join(
            line for line in preset_text("sensorless").splitlines() if "log_every" not in line
        )
    )
    assert silent.simulation.log_every == 10  # the new default, not the baseline's 1


def test_every_preset_has_a_baseline():
    assert set(BASELINE) <= set(preset_names())
    assert len(BASELINE) == 12


@pytest.mark.parametrize("name", sorted(BASELINE))
def test_preset_bit_identical_to_baseline(name):
    want = BASELINE[name]
    res = simulate(Scenario.read(name, baseline_overrides(name)))
    got = fingerprint(res, want["columns"])
    # readable first: which final value moved, then the hash over every sample
    assert got["status"] == want["status"]
    assert got["k_end"] == want["k_end"]
    assert got["final"] == want["final"]
    assert got["energy_J"] == want["energy_J"]
    assert got["compensation"] == want["compensation"]
    assert got["signals_sha256"] == want["signals_sha256"]
