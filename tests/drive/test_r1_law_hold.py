"""The online R1 law is held while the speed reference moves and the drive settles, with or
without the R2 compensator.

The law (kernels/estimators/mras.py ``mras_r1_step``) reads the MRAS's flux error along the
current as a resistance error. During a speed ramp most of that error is the speed estimate's
lag, not R1: with the compensator off (whose gating used to be the law's only hold) the
recommended preset lost control during the ramp to 1.5 x the rated speed, at no load, on
Table IV, with R1_hat(0) = R1. Held for three rotor and three speed-loop time constants after
the reference last moved (run/blocks.py ``_r1_settle_s``), the ramp keeps control and the law
still finds R1 once the speed is steady.
"""

from __future__ import annotations

import pytest
from data.ramp import ramp_scenario

from imdrive import simulate_batch

pytestmark = pytest.mark.slow  # end to end: closed-loop runs of 8 s


def _run(machine: str, speed_pu: float, load_pu: float, R1_ratio: float):
    overrides = {
        "compensator.enabled": False,
        "injection.amplitude_pu": 0.0,
        "estimator.R2_ratio": 1.0,
        "estimator.R1_ratio": R1_ratio,
        "simulation.t_end_s": 8.0,
    }
    # up to the rated speed the torque available is the rated torque
    return ramp_scenario(machine, speed_pu, overrides, load_pu_available=load_pu)


@pytest.mark.parametrize("machine", ["paper-table-iv", "krause-3hp"])
def test_ramp_to_above_base_speed_keeps_control_and_low_speed_finds_R1(machine):
    scs = [_run(machine, 1.5, 0.0, 1.0), _run(machine, 0.1, 1.0, 0.9)]
    b = simulate_batch(scs, logs=True)
    high, low = b.metrics.itertuples()
    assert not high.lost_control and not high.diverged
    assert abs(high.speed_error_rpm) < high.speed_tolerance_rpm
    r1 = b.results[1].to_pandas()
    R1 = scs[1].machine.R1_ohm
    assert abs(r1.R1_hat_ohm.iloc[-1] / R1 - 1.0) < 0.02  # from 10 % low
    assert abs(low.speed_error_rpm) < low.speed_tolerance_rpm
