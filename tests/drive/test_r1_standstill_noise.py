"""The standstill R1 test on the realistic presets' current sensors (20 mA noise, 12-bit ADC,
0.5 % gain mismatch, offsets) and bridge: R1_hat within 3 % and both levels identified.

Until 2026-11-30 the test multiplied each period's voltage and noisy measured current and
subtracted ``sigma L1 p i`` of the measured current period by period; with these seeds it read
Aalto 2.2 kW +20.6 % and -3.6 % from 1.2 R2 and Table IV -6.8 % from 0.8 R2, and over eight
seeds per case its spread was 1.0-8.8 % (3 of 48 tests identified level A only). On sub-block
means, with T2 by least squares (kernels/r1_standstill.py), 0.3-1.1 %, at most 2.4 %.
"""

import numpy as np
import pytest

from imdrive.config.scenario import Scenario
from imdrive.run.batch import simulate_batch
from imdrive.studies.realistic_envelope import REALISTIC

CASES = [
    (m, r, seed)
    for m in ("paper-table-iv", "aalto-2.2kw", "krause-50hp")
    for r in (0.8, 1.2)
    for seed in (12, 14)
]


@pytest.mark.slow  # 12 runs of 3 s on the switching bridge
def test_two_level_test_holds_R1_on_noisy_sensors():
    scs = [
        Scenario.read(
            "injection-robust",
            [
                f'machine.preset="{m}"',
                *REALISTIC,
                f"estimator.R2_ratio={r}",
                f"sensor.seed={seed}",
                "load.torque_pu={initial=0,changes=[]}",
                "control.speed_ref_pu={initial=0,changes=[{at=0.5,to=0.2,over=1.0}]}",
                "simulation.t_end_s=3",
            ],
        )
        for m, r, seed in CASES
    ]
    res = simulate_batch(scs, logs=True, log_every=50)
    for (m, r, seed), sc, rr in zip(CASES, scs, res.results, strict=True):
        # R1_hat as the test left it: the period after the speed reference left zero
        k = int(np.argmax(rr["speed_ref_rpm"] != 0)) + 2
        ratio = rr["R1_hat_ohm"][k] / sc.machine.R1_ohm
        assert rr["R1_id_status_code"][k] == 1, (m, r, seed)  # both levels identified
        assert ratio == pytest.approx(1.0, abs=0.03), (m, r, seed, ratio)
