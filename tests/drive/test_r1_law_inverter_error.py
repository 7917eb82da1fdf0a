"""The online R1 law is held where the stator resistance's drop is below twice the inverter error
the controller compensates (kernels/ifoc.py ``r1_masked_by_inverter_error``).

On the dead-time bridge (2 us compensated as 1.6 us) at 0.3 of the rated speed and no load the
law read the residual of the compensation (its shape at the current's zero crossings) as a
resistance: on Table IV the speed ended 18 rpm off from R2_hat(0) = R2 (39 rpm from 0.7 R2),
R2_hat held 80 % of the run. Held there (R1_hat |i| = 3.2 V against (4/3) k u_c = 6.7 V), the
standstill identification's R1_hat stays and the run ends within goal, on Table IV and on the
Aalto 2.2 kW machine. Drives without compensation never hold it for this reason.
"""

from __future__ import annotations

import numpy as np
import pytest
from data.ramp import BRIDGE, ramp_scenario

from imdrive import simulate_batch
from imdrive.kernels.ifoc import CONTROL_PARAMS, CONTROL_STATE, r1_masked_by_inverter_error
from imdrive.kernels.model import MODEL_STATE


def _records(dtc_u, dk, R1, R1_gate=0.0):
    p = np.zeros(1, dtype=CONTROL_PARAMS)[0]
    s = np.zeros(1, dtype=CONTROL_STATE)[0]
    m = np.zeros(1, dtype=MODEL_STATE)[0]
    p["dtc_u"] = dtc_u
    s["ie_dk"] = dk
    m["R1_hat"] = R1
    m["R1_gate"] = R1_gate
    return p, s, m


def test_the_rule():
    p, s, m = _records(5.0, 0.25, 0.5)  # 2 (4/3) 1.25 5 = 16.7 V
    assert r1_masked_by_inverter_error(p, s, m, complex(33.0, 0.0))  # 16.5 V
    assert not r1_masked_by_inverter_error(p, s, m, complex(0.0, 34.0))  # 17.0 V
    p, s, m = _records(0.0, 0.0, 0.5)  # no compensation: never
    assert not r1_masked_by_inverter_error(p, s, m, complex(0.1, 0.0))


def test_the_gate_reads_the_identified_R1_not_the_law_s():
    # the law raising R1_hat does not open its own gate: R1_gate (the identifications') decides
    p, s, m = _records(5.0, 0.25, R1=0.6, R1_gate=0.5)
    assert r1_masked_by_inverter_error(p, s, m, complex(33.0, 0.0))  # 0.5 * 33 = 16.5 V
    p, s, m = _records(5.0, 0.25, R1=0.4, R1_gate=0.5)
    assert not r1_masked_by_inverter_error(p, s, m, complex(34.0, 0.0))  # 17.0 V


@pytest.mark.slow  # end to end: switching-bridge runs of 24 s
@pytest.mark.parametrize("machine", ["paper-table-iv", "aalto-2.2kw"])
def test_bridge_no_load_low_speed_within_goal(machine):
    scs = [
        ramp_scenario(
            machine,
            0.3,
            BRIDGE
            | {
                "estimator.R2_ratio": ratio,
                "estimator.R1_ratio": 1.1,
                "load.torque_Nm": 0.0,
                "simulation.t_end_s": 24.0,
            },
        )
        for ratio in (1.0, 0.7)
    ]
    for row in simulate_batch(scs).metrics.itertuples():
        assert abs(row.R2_error_pct) < 3.0, row.verdict_text
        assert abs(row.speed_error_rpm) < row.speed_tolerance_rpm, row.verdict_text


@pytest.mark.slow  # end to end: a 16 s run of the realistic drive
def test_the_law_does_not_open_its_own_gate_on_the_realistic_drive():
    # the realistic presets' drive on the Aalto 2.2 kW machine at half the rated speed, no
    # load: R1 |i| sits near the bare threshold (4/3) k u_c. There the law read the residual
    # as R1, raised R1_hat and with it its own gate's R1, climbed to 1.3-1.36 R1 and the drive
    # lost control; held by the identified R1 with the margin, R1_hat stays the test's
    from imdrive.studies.realistic_envelope import scenarios

    scs, _ = scenarios(
        machines=("aalto-2.2kw",), speeds=(0.5,), loads=(0.0,), ratios=(1.2,), seeds=(1,)
    )
    res = simulate_batch(scs, logs=True).results[0]
    assert not res.lost_control
    assert res["R1_hat_ohm"][-1] / scs[0].machine.R1_ohm == pytest.approx(1.0, abs=0.04)
