"""The model-based R2 law closes a large initial R2 error with a bounded overshoot.

From R2_hat(0) = 0.7 R2 the first windows read a large negative error up to 1.9 times its
linear prediction (kernels/r2_kalman.py, ``GAIN_UNCERTAINTY``), so R2_hat overshoots before it
settles: measured +2.7 % on the 2.2 kW Aalto machine and +2.9 % on Krause 50 hp at half speed
and rated torque, +0.8 % on Table IV at 0.1 of the rated speed. With the measured error's
variance not carried through to R2 (``dz/dr``) it was +3.8 and +5.6 %. The adaptive law of
earlier releases kept under 1 %; the Kalman law that replaced it is held to 4 % and to the
same settling, within 0.5 % at the end.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from imdrive.errors import ConfigWarning
from imdrive.run.simulate import simulate
from imdrive.studies.machines import scenarios

#: The largest excursion above R2 the law keeps to, %
OVERSHOOT_PCT = 4.0


@pytest.mark.slow
@pytest.mark.parametrize(
    ("machine", "speed_pu"), [("aalto-2.2kw", 0.5), ("paper-table-iv", 0.1), ("krause-50hp", 0.5)]
)
def test_bounded_overshoot_from_0_7_R2(machine, speed_pu):
    (sc,), _ = scenarios([machine], ["injection-robust"], [speed_pu], [1.0], [0.7])
    assert sc.compensator.step_law == "kalman"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        res = simulate(sc.with_overrides(["simulation.log_every=100"]))
    assert res.status == 0
    err = 100.0 * (np.asarray(res["R2_hat_ohm"]) / np.asarray(res["R2_ohm"]) - 1.0)
    assert err[0] == pytest.approx(-30.0, abs=0.01)
    assert err.max() < OVERSHOOT_PCT
    assert abs(err[-1]) < 0.5


@pytest.mark.slow
def test_krause_50hp_near_zero_stator_frequency_from_0_8_R2_converges():
    """Krause 50 hp regenerating the rated torque at +2 Hz of stator frequency from
    R2_hat(0) = 0.8 R2 (``studies/zero_frequency.py``'s cell). There the detuned drive
    oscillates at 2.25 Hz; with the variance of ``r`` alone one window took R2_hat to its
    clamp at 2 R2, with the variance carried through ``dz/dr`` it ended 40 % low (the
    injection at 2.24 Hz, 0.28 Hz from the stator frequency, reading the oscillation), and
    since the schedule passes over harmonics within its band of the stator frequency
    (kernels/gating.py, ``injection_by_response``) it converges: within 2 % at the end, never
    above R2 by more than the overshoot bound on the way."""
    from imdrive.studies import zero_frequency

    scs, _ = zero_frequency.scenarios(
        machines=["krause-50hp"], frequencies=(2.0,), ratios=(0.8,), drives=("injection-robust",)
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        res = simulate(scs[0])
    ratio = np.asarray(res["R2_hat_ohm"]) / np.asarray(res["R2_ohm"])
    assert ratio[0] == pytest.approx(0.8, abs=1e-3)
    assert ratio.max() < 1.0 + OVERSHOOT_PCT / 100.0  # was 2.0: the clamp
    assert abs(ratio[-1] - 1.0) < 0.02  # was -40 %
    assert res.verdict["verdict_ok"], res.verdict["verdict_text"]
