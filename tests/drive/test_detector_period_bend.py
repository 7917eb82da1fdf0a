"""The R2 detection of an estimator without a flux error (the AFO) takes the period's mean
current with its bend, as the MRAS does (kernels/flux_detector.py).

Without the bend the detection's two flux models read a zero error at an R2_hat that followed
the injection frequency, which is set from R2_hat(0)'s rotor corner: at twice the rated speed
regenerating half the rated torque the observer drive's R2_hat ended -0.42 / +0.12 % off from
0.7 / 1.3 R2 on Table IV, -0.31 / +0.06 % on the Aalto 2.2 kW machine and -0.76 / +0.14 % on
Krause 50 hp. With it, within 0.21 % and the two starts within 0.21 % of each other (measured
2026-11-30). The claims: where R2_hat ends does not depend on where it started; and the
detector's two models are the MRAS's, so the MRAS drive with its detection formed by the
detector ends where it ends with the MRAS's own flux error (without the bend: -0.53 % against
+0.07 % from 0.7 R2 at twice the rated speed regenerating half the rated torque, Table IV).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import imdrive.run.blocks as blocks
import imdrive.run.compensator_blocks as compensator_blocks
from imdrive import simulate_batch
from imdrive.run.simulate import simulate
from imdrive.studies import machines as envm

MACHINES = ("paper-table-iv", "aalto-2.2kw", "krause-50hp")
STARTS = (0.7, 1.3)


@pytest.mark.slow  # 6 closed-loop runs of the machine envelope's timeline
def test_the_observer_drives_R2_hat_ends_where_R2_is_from_either_side():
    scs = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for machine in MACHINES:
            got, _ = envm.scenarios(
                [machine], drives=["injection-robust-afo"], speeds=(2.0,), loads=(-0.5,),
                ratios=STARTS,
            )  # fmt: skip
            scs += got
    m = simulate_batch(scs).metrics
    err = np.asarray(m["R2_error_pct"]).reshape(len(MACHINES), len(STARTS))
    assert (m["verdict"] == "ok").all()
    assert np.abs(err).max() < 0.3, err
    assert np.abs(err[:, 0] - err[:, 1]).max() < 0.3, err


@pytest.mark.slow  # 2 closed-loop runs of the machine envelope's timeline
def test_the_detector_is_the_mras_s_own_pair_of_models(monkeypatch):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        (sc,), _ = envm.scenarios(
            ["paper-table-iv"], drives=["injection-robust-mras"], speeds=(2.0,), loads=(-0.5,),
            ratios=(0.7,),
        )  # fmt: skip
        # the formed error has its stationary-frame mean removed (kernels/detection.py): the
        # MRAS's own gets the same stage here, so that the two differ only by their models
        fields = compensator_blocks.compensator_fields

        def with_mean_out(scenario, D):
            record, derived = fields(scenario, D)
            return {**record, "mean_out": True}, derived

        monkeypatch.setattr(blocks, "compensator_fields", with_mean_out)
        own = simulate(sc).metrics()
        # every estimator treated as one that gives no flux error: the detector forms it
        monkeypatch.setattr(compensator_blocks, "gives_flux_error", lambda speed_feedback: False)
        formed = simulate(sc).metrics()
    r_own, r_formed = own["R2_error_pct"], formed["R2_error_pct"]
    assert abs(r_own) < 0.2, r_own
    assert r_formed == pytest.approx(r_own, abs=0.01), r_formed
