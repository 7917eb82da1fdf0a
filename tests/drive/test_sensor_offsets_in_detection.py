"""The recommended drive on the realistic drive at low speed: the current sensors' offsets no
longer reach the R2 detection (kernels/detection.py ``stationary_mean_removed``).

The realistic presets' phase sensors read 20 mA off (opposite signs) with 20 mA of noise. The
offsets put a constant into the detection's flux error in the stationary frame; before its
mean was removed these cells ended with R2_hat 2.2-3.9 % off (flagged ``R2-off``), on the
noise seeds given. Each is run with its own status (:mod:`imdrive.studies.realistic_envelope`).
"""

from __future__ import annotations

import pandas as pd
import pytest

from imdrive.studies import realistic_envelope as study


@pytest.mark.slow
def test_low_speed_cells_hold_r2_within_the_goal():
    t = pd.concat(
        [
            # the Aalto 2.2 kW machine at 0.2 and 0.3 of the rated speed, regenerating and
            # motoring the rated torque, from either side (noise seed 4): before, 0.2 pu
            # regenerating from 1.2 R2 ended +3.9 %, 0.3 pu regenerating from 0.8 R2 +3.3 %
            study.measure(
                machines=("aalto-2.2kw",),
                speeds=(0.2, 0.3),
                loads=(-1.0, 1.0),
                ratios=(0.8, 1.2),
                seeds=(4,),
            ),  # fmt: skip
            # Krause's 3 hp and Table IV at 0.3 pu unloaded from 0.8 R2 (seed 1): +2.2 % and
            # +1.1 % before
            study.measure(
                machines=("krause-3hp", "paper-table-iv"),
                speeds=(0.3,),
                loads=(0.0,),
                ratios=(0.8,),
                seeds=(1,),
            ),  # fmt: skip
        ]
    )
    assert len(t) == 10
    assert not t["lost_control"].astype(bool).any()
    bad = t[(t.verdict != "ok") | (t.R2_error_pct.abs() > 2.0)]
    assert bad.empty, bad[["machine", "speed_pu", "load_pu", "R2_ratio", "R2_error_pct"]]
