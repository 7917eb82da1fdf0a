"""The first-release tuning of the injection presets (tests/data/first_release.py) is still
reachable bit for bit: the tests that reproduce a finding with it start from the same runs
as before the presets got the recommended mechanisms."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from data.first_release import first_release
from data.make_preset_baseline import fingerprint

from imdrive.run.simulate import simulate

STORED = json.loads(
    (Path(__file__).resolve().parents[1] / "data" / "first_release_baseline.json").read_text()
)


@pytest.mark.parametrize("name", sorted(STORED))
def test_first_release_tuning_is_bit_identical(name):
    res = simulate(first_release(name))
    got = fingerprint(res, STORED[name]["columns"])
    assert got["signals_sha256"] == STORED[name]["signals_sha256"]
