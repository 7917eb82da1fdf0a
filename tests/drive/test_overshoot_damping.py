"""The adaptive step law's overshoot damping (kernels/step_damping.py) in the drive: at 20 rpm
with rated motoring torque from R2_hat(0) = 1.3 R2 the injection runs at its third frequency,
where the detection is more sensitive than the table was drawn for, and the table's steps
limit-cycled R2_hat by +-10.5 % on Table IV; damped, the swing over the last 10 s is a
seventh of that (1.5 %). The limit cycle needs a large first overshoot to start: on Krause's
3 hp machine it appeared with the envelope sweep's profile (Table IV's 12.4 N m, 4 % above its
rated torque: +-7.2 %, damped +-2.8 %) but not at its own rated torque (+-0.6 % either way),
so the kernel's rule is tested on its own in tests/kernels/test_step_damping.py.

The fine step's gain following R2_hat (``compensator.fine_gain_follows_R2``,
kernels/sensitivity.py ``fine_loop_gain_ratio``: approaching from 1.3 R2 it is 0.79 of the
tuned one at R2) keeps this limit cycle from starting as well (undamped +-0.73 %, damped
+-0.10 %), so the test pins the fixed fine gain it was measured with."""

from __future__ import annotations

import numpy as np
import pytest
from data.ramp import ADAPTIVE_LAW

from imdrive.config.rated import rated_point
from imdrive.config.scenario import Scenario
from imdrive.run.batch import simulate_batch

pytestmark = pytest.mark.slow

T_END_S = 30.0
WINDOW_S = 10.0


def _scenario(machine: str, damping: bool) -> Scenario:
    base = Scenario.read("injection-robust", [f'machine.preset="{machine}"']).with_overrides(
        ADAPTIVE_LAW
    )
    rp = rated_point(base.machine)
    n, T = 0.0116 * rp.speed_rpm, rp.torque_Nm
    return base.with_overrides(
        [
            f"control.speed_ref_rpm={{initial=0, changes=[{{at=0.5, to={n}, over=3.0}}]}}",
            f"load.torque_Nm={{initial=0, changes=[{{at=4.0, to={T}}}]}}",
            "injection.t_on_s=5.0",
            "compensator.t_on_s=5.0",
            "estimator.R2_ratio=1.3",
            "estimator.R1_ratio=0.9",
            f"simulation.t_end_s={T_END_S}",
            "simulation.log_every=100",
            f"compensator.overshoot_damping={'true' if damping else 'false'}",
            "compensator.fine_gain_follows_R2=false",  # the fine gain it was measured with
        ]
    )


@pytest.fixture(scope="module")
def swings():
    cases = [("paper-table-iv", d) for d in (False, True)]
    batch = simulate_batch([_scenario(m, d) for m, d in cases], logs=True)
    out = {}
    for case, res in zip(cases, batch.results, strict=True):
        df = res.to_pandas()
        last = df[df["time_s"] > T_END_S - WINDOW_S]
        err = 100.0 * (last["R2_hat_ohm"] / last["R2_ohm"] - 1.0)
        out[case] = float(np.max(np.abs(err)))
    return out


def test_the_table_steps_limit_cycle_undamped_and_settle_damped(swings):
    undamped, damped = swings[("paper-table-iv", False)], swings[("paper-table-iv", True)]
    assert undamped > 5.0  # the limit cycle the damping is for
    assert damped < undamped / 3.0
