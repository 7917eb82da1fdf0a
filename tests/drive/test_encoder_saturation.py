"""The recommended R2 law on an encoder drive with a saturating machine
(``control.speed_feedback = "measured"``, the MRAS beside, the controller with the plant's
magnetising curve): the magnetising curve is read at the MRAS's flux magnitude, which an
R̂2 error does not move (kernels/ifoc.py ``foc_step``, ``psi_mag``).

With an encoder an R̂2 error detunes the real flux (sensorless it becomes a speed error
instead); at its own flux model's magnitude the controller did not see it, the machine's
incremental inductance moved with the flux, and the law read that as an R2 error of the
wrong sign: from 0.95 and 1.05 R2 R̂2 ran to -49 and +121 % at half the rated speed, from
0.8 and 1.2 R2 to the clamps, and 2 of 12 runs lost control (Table IV; the Aalto 2.2 kW
machine alike). Measured 2026-11-30 with the MRAS's magnitude, at 0.5 and 1 of the rated
speed, regenerating, unloaded and motoring the rated torque, from 0.8 and 1.2 R2: within
1.4 % on Table IV, the Aalto machine and Krause 3 hp. At 0.2 of the rated speed from 0.8 R2
R̂2 still climbs to its clamp on Table IV and Krause 3 hp (not solved; from 1.2 R2 within
2.3 %). At half the rated speed regenerating the rated torque from below R2, R̂2 swings between
about 0.9 and 1.2 R2 over some 10 s (without saturation it settles): from 0.80 R2 the run ends
-1.37 % on Table IV, from 0.81 R2 -6.7 %, and Krause 3 hp -0.42 and -3.36 % (measured
2026-11-30). The 0.8 start here passes by the phase at which the swing ends; the swing is open
(issue 38).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest


@pytest.mark.slow
def test_an_encoder_drive_tracks_R2_on_a_saturating_machine(monkeypatch):
    from imdrive.run.batch import simulate_batch
    from imdrive.studies import realistic_envelope as re_

    monkeypatch.setattr(
        re_,
        "REALISTIC",
        (
            'control.speed_feedback="measured"',
            "plant.saturation.enabled=true",
            "controller_model.ideal=true",
        ),
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scs, rows = re_.scenarios(
            machines=("paper-table-iv", "aalto-2.2kw"), speeds=(0.5, 1.0), loads=(-1.0, 1.0),
            ratios=(0.8, 1.2), seeds=(1,),
        )  # fmt: skip
        res = simulate_batch(scs, errors="record")
    m = res.metrics
    assert not m["lost_control"].astype(bool).any()
    err = m["R2_error_pct"].to_numpy()
    assert np.all(np.abs(err) < 2.0), rows.assign(R2_error_pct=err)
