"""Regenerating below the rated slip frequency on the observer drive (injection-robust), the
injection's frequency follows the detection's modelled response (kernels/gating.py,
injection_by_response): R2 is tracked at points where, at the first frequency, R2_hat walked
away. Three machines, three studies' cells."""

from __future__ import annotations

import warnings

import pytest

from imdrive import simulate
from imdrive.errors import ConfigWarning
from imdrive.studies import machines, zero_frequency
from imdrive.sweep.spec import load_sweep

pytestmark = pytest.mark.slow


@pytest.mark.parametrize(("run", "R1_ratio", "bound_pct"), [(1083, 0.9, 3.0), (1087, 1.1, 5.0)])
def test_table_iv_on_the_bridge_through_a_thermal_ramp_regenerating_at_a_tenth_of_rated_speed(
    run, R1_ratio, bound_pct
):
    """``envelope-full``'s cells: 0.1 of the rated speed, regenerating the rated torque, from
    R2_hat(0) = 0.7 R2, R2 +20 % over 30 s, dead-time bridge. The ramp takes the stator
    frequency from 3.1 Hz to below the rated slip frequency (2.6 Hz), where the first
    frequency (1.17 Hz) reads R2 with the wrong sign: R2_hat ran to +8.7 % (R1_hat = 0.9 R1)
    and +19 % (1.1 R1) until 2026-12-01. Then -1.8 % and -3.7 % (flagged ``R2-off``); with the
    Kalman law's variance carried to R2, -0.85 % at the end and -2.2 % within the final window
    (within the bridge's 3 % goal; flagged ``R2-unsettled`` by the status's own 2 %) and
    -3.05 % (flagged). The status is ``ok`` exactly when both are within its 2 %."""
    sw = load_sweep("envelope-full")
    row = sw.inputs(range(run, run + 1)).iloc[0]
    assert (row["speed_pu"], row["load_pu_available"], row["R2_ratio"]) == (0.1, -1.0, 0.7)
    assert (row["R1_ratio"], row["thermal"], row["inverter"]) == (R1_ratio, "ramp", "bridge")
    res = simulate(sw.scenario(run))
    m = res.metrics(window_s=0.5)
    assert abs(m["R2_error_pct"]) < bound_pct
    assert abs(m["R2_error_window_pct"]) < bound_pct
    settled = max(abs(m["R2_error_pct"]), abs(m["R2_error_window_pct"])) <= 2.0
    assert res.verdict["verdict_ok"] == settled


def _cell(scs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        return simulate(scs[0])


def test_krause_50hp_regenerating_at_a_tenth_of_rated_speed_from_above():
    """The machine envelope's cell that ended +17.8 % (R2_hat(0) = 1.2 R2)."""
    scs, _ = machines.scenarios(
        machines=["krause-50hp"], drives=("injection-robust",), speeds=(0.1,), loads=(-1.0,),
        ratios=(1.2,),
    )  # fmt: skip
    res = _cell(scs)
    m = res.metrics(window_s=0.5)
    assert abs(m["R2_error_pct"]) < 2.0
    assert not res.lost_control


def test_krause_500hp_regenerating_at_a_quarter_hertz():
    """The zero-frequency study's cell that ended +25 % (R2_hat(0) = 1.2 R2, +0.25 Hz)."""
    scs, _ = zero_frequency.scenarios(
        ["krause-500hp"], (0.25,), (1.2,), drives=("injection-robust",)
    )
    res = _cell(scs)
    m = res.metrics(window_s=0.5)
    assert abs(m["R2_error_pct"]) < 2.0
    assert not res.lost_control
