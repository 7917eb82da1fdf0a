"""The compensator's records take their constants from the drive actually running
(imdrive.run.compensator_blocks)."""

from __future__ import annotations

import pytest

from imdrive import Scenario
from imdrive.run.build import build_arrays


@pytest.mark.parametrize(
    ("overrides", "wc"),
    [
        ([], 15.0),  # the MRAS's own filter
        (["mras.wc_rad_s=12"], 12.0),
        # the sliding-mode MRAS hands the detection its own flux error: its own filter
        (['control.speed_feedback="smo-mras"', "smo_mras.wc_rad_s=9", "mras.wc_rad_s=12"], 9.0),
        # the observer gives none: the detector's two models, built with [mras]'s corner
        (['control.speed_feedback="afo"', "mras.wc_rad_s=11"], 11.0),
    ],
)
def test_the_slip_decoupling_undoes_the_filter_of_the_running_estimator(overrides, wc):
    comp = build_arrays(Scenario.read("injection-robust", overrides)).params.comp[0]
    assert comp["cpl_wc"] == wc
