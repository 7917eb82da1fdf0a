"""The field weakening and the estimation headroom see the modulator's whole voltage, the
inverter-error compensation included.

On the dead-time bridge the compensation adds a few percent of the voltage limit, along the
current. The voltage the controller keeps for its estimator leaves it out (it cancels the dead
time's loss); the field weakening read that too, held it at its target and left the
compensation no room: the sum reached the limit, the current PIs lost authority and above the
rated speed the drive lost control (Table IV at 1.5 x the rated speed, no load, R2_hat(0) =
1.3 R2, 2 us of dead time compensated as 1.6 us). Reading the commanded total
(``SAMPLE_STATE.v_use``) it keeps control.
"""

from __future__ import annotations

import pytest
from data.ramp import BRIDGE, ramp_scenario

from imdrive import Scenario, simulate_batch

pytestmark = pytest.mark.slow  # end to end: switching-bridge runs of 12 s


def _scenario(machine: str, speed_pu: float) -> Scenario:
    overrides = BRIDGE | {
        "estimator.R2_ratio": 1.3,
        "estimator.R1_ratio": 1.1,
        "load.torque_Nm": 0.0,
        "simulation.t_end_s": 12.0,
    }
    return ramp_scenario(machine, speed_pu, overrides)


@pytest.mark.parametrize("machine", ["paper-table-iv", "aalto-2.2kw"])
def test_bridge_above_rated_speed_keeps_control(machine):
    b = simulate_batch([_scenario(machine, -1.5), _scenario(machine, 1.5)])
    for row in b.metrics.itertuples():
        assert not row.lost_control and not row.diverged, row.verdict_text
