"""The compensator's speed-transient gate weighs the speed error by the speed loop's gain, so
R̂2 converges in deep field weakening (kernels/speed_control.py ``speed_loop_gain``).

With the speed PI's gains scaled by the flux factor ``k`` the loop's gain falls as ``k^2``
(0.14 at twice the rated speed on Table IV), and the speed error's area after any event grows
as ``1/k^2``. Each of the compensator's own R̂2 steps moves the speed estimate by the step's
share of the slip; at 2 x and full load the slow loop left a period-mean speed error above the
gate's 1 rpm for the next decision, and the hold after it: from R̂2(0) = 0.7 R2 the gate
held R̂2 most of the time, and under a heating ramp it ended 6.4 % low (24 rpm off). Weighted
by the loop's gain the threshold keeps its rated-flux meaning and R̂2 converges in a few
seconds; the reference's own moves are still compared unweighted.
"""

from __future__ import annotations

import numpy as np
import pytest
from data.ramp import ramp_scenario

from imdrive import simulate_batch
from imdrive.kernels.compensator import (
    COMPENSATOR_PARAMS,
    COMPENSATOR_STATE,
    compensator_gate_sample,
)
from imdrive.kernels.ifoc import CONTROL_PARAMS
from imdrive.kernels.speed_control import speed_loop_gain

RPM = np.pi / 30.0


def test_loop_gain_is_one_at_rated_flux_and_k_or_k_squared_below():
    p = np.zeros(1, CONTROL_PARAMS).view(np.recarray)[0]
    p.w_fw_sched = True
    assert speed_loop_gain(p, 1.0) == 1.0  # rated flux: the gate as it was, bit for bit
    assert speed_loop_gain(p, 1.0 - 0.6) == pytest.approx(0.16)  # fw_cut 0.6
    p.w_fw_sched = False  # unscaled gains: only the torque constant falls
    assert speed_loop_gain(p, 0.4) == pytest.approx(0.4)


def test_weighted_error_flags_only_above_the_rated_flux_threshold():
    """A 3 rpm mean error trips the 1 rpm gate at rated flux, not at k = 0.38 (k^2 = 0.144);
    a reference move of 3 rpm trips it at any flux."""
    p = np.zeros(1, COMPENSATOR_PARAMS).view(np.recarray)[0]
    p.gate_dw, p.gate_v = 1.0 * RPM, 2.0

    def flags(g_w, w_ref_end):
        s = np.zeros(1, COMPENSATOR_STATE).view(np.recarray)[0]
        for w_ref in np.linspace(100.0, w_ref_end, 50):
            compensator_gate_sample(p, s, w_ref, w_ref - 3.0 * RPM, 0.0, 0.5, 10.0, g_w)
        return int(s.g_flags) | (1 if abs(s.g_err / s.g_cnt) > p.gate_dw else 0)

    assert flags(1.0, 100.0) & 1
    assert not flags(0.144, 100.0) & 1
    assert flags(0.144, 100.0 + 3.0 * RPM) & 1


def _scenario(machine: str):
    overrides = {
        "estimator.R2_ratio": 0.7,
        "estimator.R1_ratio": 1.0,
        "simulation.t_end_s": 22.0,
        "simulation.log_every": 100,
    }
    return ramp_scenario(machine, 2.0, overrides, load_pu_available=1.0)


@pytest.mark.slow
@pytest.mark.parametrize("machine", ["paper-table-iv", "krause-3hp"])
def test_r2_converges_at_twice_rated_speed_and_full_load(machine):
    """17 s after the compensator's start, from R̂2(0) = 0.7 R2: within 2 %, and held well
    under the unweighted gate's share (-6.8 %, held 68 and 66 % of the time). The Kalman law
    decides on whole injection periods and settles two of them after a frequency switch: held
    35 % on Krause 3 hp (the adaptive law's half-period decisions held 15-18 %; the cost is in
    CHANGELOG.md)."""
    row = next(simulate_batch([_scenario(machine)]).metrics.itertuples())
    assert abs(row.R2_error_pct) < 2.0
    assert row.R2_held_pct < 40.0
