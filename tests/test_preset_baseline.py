"""Every preset gives bit for bit the results stored before the layout refactor (issue 14).

``tests/data/preset_baseline.json`` holds, per preset, the status, the number of periods, the
final value of every column, the energies, the compensation metrics and a SHA-256 of every
logged column. It was written by ``tests/data/make_preset_baseline.py`` from the first release
(commit 6816c96) before any code moved; regenerate it only for an intended change of numerics.
"""

import json
from pathlib import Path

import pytest
from data.make_preset_baseline import fingerprint

from imdrive.config.presets import preset_names
from imdrive.config.scenario import Scenario
from imdrive.run.simulate import simulate

BASELINE = json.loads((Path(__file__).parent / "data" / "preset_baseline.json").read_text())


def test_every_preset_has_a_baseline():
    assert set(BASELINE) <= set(preset_names())
    assert len(BASELINE) == 12


@pytest.mark.parametrize("name", sorted(BASELINE))
def test_preset_bit_identical_to_baseline(name):
    want = BASELINE[name]
    res = simulate(Scenario.read(name))
    got = fingerprint(res, want["columns"])
    # readable first: which final value moved, then the hash over every sample
    assert got["status"] == want["status"]
    assert got["k_end"] == want["k_end"]
    assert got["final"] == want["final"]
    assert got["energy_J"] == want["energy_J"]
    assert got["compensation"] == want["compensation"]
    assert got["signals_sha256"] == want["signals_sha256"]
