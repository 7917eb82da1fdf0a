"""The adaptive law's drift term is off near the MRAS filter's corner (run/blocks.py
``_drift_fmin``; kernels/compensator.py, the adaptive law).

At 0.1 x rated speed, regenerating at the rated torque, from R2_hat(0) = 0.8 R2, the stator
frequency (3.2 Hz on Krause 3 hp, 2.5 Hz on Krause 50 hp) was above the higher injection
frequency (2.7 and 1.5 Hz), so the drift term ran, and R2_hat swung around R2 with a period of
about 10 s: the machine envelope's runs ended -2.5 and -2.9 % off. Off below 1.75 times the
filter's corner (4.2 Hz with wc = 15 rad/s), they end within 2 %.

The test pins the fixed corner it was measured with (``mras.wc_per_stator_frequency = 0``):
with the recommended preset's corner that follows the stator frequency (10 rad/s there) the
swing is gone with the drift term on as well (Krause 3 hp: -0.77 %).

Since the drift is not integrated towards the error while the error shrinks (the adaptive
law's overshoot, kernels/compensator.py), the approach from 0.8 R2 no longer winds it up:
with the drift term forced on here the runs are the same as without it to 0.01 % (-0.08 and
-1.5 %; the same to the last digit until a shrink of less than 5 % of the error per decision
counted as a ramp's lag, kernels/drift_rate.py), where they swung before.
"""

from __future__ import annotations

import pytest

from imdrive import simulate_batch
from imdrive.studies.machines import scenarios, timeline

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("machine", ["krause-3hp", "krause-50hp"])
def test_low_frequency_regeneration_converges_without_the_drift_term(machine):
    scs, _ = scenarios([machine], drives=["injection-robust"], speeds=[0.1], loads=[-1.0],
                       ratios=[0.8])  # fmt: skip
    sc = scs[0].with_overrides({"mras.wc_per_stator_frequency": 0.0})  # the fixed corner
    # the load steps at the grid's time as measured, without the standstill test's wait
    # (studies/machines.py standstill_wait_s): 0.08 s later on Krause 3 hp, the drift term
    # moves the end by 0.04 % of R2 (-0.11 -> -0.15 %)
    T = sc.load.torque_Nm.points[-1][1]
    load_at = timeline(sc.machine)[1]
    sc = sc.with_overrides([f"load.torque_Nm={{initial=0, changes=[{{at={load_at}, to={T}}}]}}"])
    old = sc.with_overrides({"compensator.drift_min_freq_Hz": 0.0})  # drift term always on
    new, was = simulate_batch([sc, old]).metrics.itertuples()
    # with the drift term on the swing ran to the end (measured -2.5 / -2.9 % with the higher
    # injection frequency as the bound; larger with none); now it is never wound up here
    # forcing the drift term off changes the end by a hair (the fine gain follows R2_hat)
    assert was.R2_error_pct == pytest.approx(new.R2_error_pct, abs=0.01)
    # measured -0.11 / -0.09 % (Krause 50 hp: -1.5 % while its standstill window came after
    # the ramp and R1_hat stayed 10 % off)
    assert abs(new.R2_error_pct) < 2.0, new.R2_error_pct
    assert new.verdict == "ok", new.verdict_text
