"""The adaptive law's drift rate (kernels/drift_rate.py) and its fine-band gain ratio
(kernels/sensitivity.py ``fine_loop_gain_ratio``) on hand-made records: a drift against the
error unwinds faster than it winds and stops at zero, a slowly shrinking error (a ramp's lag
as the detection's sensitivity drifts) winds it, the proportional step closing an error does
not; the fine gain follows R2_hat's share of the tuned R2 and the injection's sensitivity."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imdrive.kernels.compensator import COMPENSATOR_PARAMS, COMPENSATOR_STATE
from imdrive.kernels.drift_rate import drift_update
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.records import new_record
from imdrive.kernels.sensitivity import fine_loop_gain_ratio, in_phase_sensitivity

GAIN = 0.3  # drift_gain
UNWIND = 4.0
MARGIN = 0.05
P = new_record(
    COMPENSATOR_PARAMS, drift_gain=GAIN, drift_max=1.0, drift_unwind=UNWIND, drift_margin=MARGIN
)[0]


def _state(drift: float):
    s = np.zeros(1, dtype=COMPENSATOR_STATE)[0]
    s["drift"] = drift
    return s


def test_a_drift_against_the_error_unwinds_faster_and_stops_at_zero():
    s = _state(0.01)
    drift_update(P, s, -0.1, -0.01, -0.001)  # the error grows against the drift
    assert s["drift"] == pytest.approx(0.01 - UNWIND * GAIN * 0.001)
    s = _state(0.01)
    drift_update(P, s, -0.1, 0.01, -0.001)  # against it but shrinking: the plain gain
    assert s["drift"] == pytest.approx(0.01 - GAIN * 0.001)
    for dx in (-0.1, 0.1):  # would cross zero: stops there, growing or shrinking
        s = _state(0.001)
        drift_update(P, s, -0.5, dx, -0.01)
        assert s["drift"] == 0.0


def test_a_slowly_shrinking_error_winds_the_drift_a_closing_one_does_not():
    x = 0.2
    slow = _state(0.0)
    drift_update(P, slow, x, -0.5 * MARGIN * x, 0.002)
    assert slow["drift"] == pytest.approx(GAIN * 0.002)
    closing = _state(0.0)
    drift_update(P, closing, x, -2.0 * MARGIN * x, 0.002)
    assert closing["drift"] == 0.0
    growing = _state(0.0005)  # the error growing with the drift's sign: winds at the plain gain
    drift_update(P, growing, x, 0.01, 0.002)
    assert growing["drift"] == pytest.approx(0.0005 + GAIN * 0.002)


def test_a_record_without_the_settings_keeps_the_plain_rule():
    p = new_record(COMPENSATOR_PARAMS, drift_gain=GAIN, drift_max=1.0)[0]
    s = _state(0.01)
    drift_update(p, s, -0.1, -0.01, -0.001)  # no faster unwinding
    assert s["drift"] == pytest.approx(0.01 - GAIN * 0.001)
    s = _state(0.0)
    drift_update(p, s, 0.2, -1e-6, 0.002)  # any shrink counts as closing
    assert s["drift"] == 0.0
    s = _state(0.001)
    drift_update(p, s, -0.5, 0.1, -0.01)  # unwound past zero, as the plain law did
    assert s["drift"] == pytest.approx(0.001 - GAIN * 0.01)


def _ratio(R2_hat: float, R2_tuned: float, f_inj: float = 1.1666) -> float:
    p = new_record(COMPENSATOR_PARAMS, inj_freq=f_inj, R2_tuned=R2_tuned)[0]
    m = new_record(MODEL_STATE, R2_hat=R2_hat, Ll2_hat=0.0024, M_hat=0.069)[0]
    return fine_loop_gain_ratio(p, m)


def test_fine_gain_follows_R2_hat_and_the_injections_sensitivity():
    R2_0 = 0.7 * 0.816
    assert _ratio(R2_0, R2_0) == pytest.approx(1.0)
    assert _ratio(R2_0, 0.0) == 1.0  # no tuned R2: the fixed gain
    # heated to 1.2 R2 from R2_hat(0) = 0.7 R2: the step's share and the sensitivity
    R2 = 1.2 * 0.816
    w = 2.0 * math.pi * 1.1666
    L2 = 0.0714  # Ll2 + M of Table IV, H
    want = (R2 / R2_0) * in_phase_sensitivity(w, L2 / R2_0) / in_phase_sensitivity(w, L2 / R2)
    assert _ratio(R2, R2_0) == pytest.approx(want)
    assert 2.0 < want < 3.0
    assert _ratio(100.0 * R2_0, R2_0) == 4.0  # bounded
    assert 0.25 <= _ratio(0.3 * R2_0, R2_0) <= 4.0
