"""Overshoot damping of the adaptive step law's table levels (kernels/step_damping.py): a
table-level step against the last one's sign halves the steps that follow, steps of one sign
take that back slowly, a start far from R2 is not slowed."""

from __future__ import annotations

import numpy as np
import pytest

from imdrive.fuzzy import fuzzy_table
from imdrive.kernels.compensator import (
    COMPENSATOR_PARAMS,
    COMPENSATOR_STATE,
    compensator_update,
)
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.records import new_record
from imdrive.kernels.step_damping import (
    DAMP_MAX_HALVINGS,
    DAMP_RECOVERY,
    table_step_factor,
)

G_CR = 0.01
GAIN = 1e3  # scaled input per Wb: E = 4 mWb gives x = 4, a table level well outside the fine band


def _bench(damp: bool):
    p = new_record(
        COMPENSATOR_PARAMS,
        enabled=True,
        n=10,
        G_E=GAIN,
        G_DE=GAIN,
        G_CR=G_CR,
        R2_min=0.1,
        R2_max=10.0,
        average=True,
        fine=True,
        fine_gain=1.0,
        damp=damp,
    )[0]
    s = np.zeros(1, dtype=COMPENSATOR_STATE)[0]
    m = new_record(MODEL_STATE, R2_hat=1.0)[0]
    return p, s, m, fuzzy_table("paper").astype(float)


def _steps(damp: bool, inputs) -> list[float]:
    p, s, m, table = _bench(damp)
    out = []
    for E in inputs:
        before = float(m["R2_hat"])
        compensator_update(p, s, m, table, E)
        out.append(float(m["R2_hat"]) - before)
    return out


def test_steps_of_one_sign_are_the_tables_own():
    same = [4e-3] * 6
    assert _steps(True, same) == _steps(False, same)


def test_alternating_steps_are_halved_down_to_a_quarter():
    alternating = [4e-3, -4e-3] * 4
    plain = np.abs(_steps(False, alternating))
    damped = np.abs(_steps(True, alternating))
    ratio = damped / plain
    # the first step is the table's; each reversal halves, down to 0.5 ** DAMP_MAX_HALVINGS
    assert ratio[0] == pytest.approx(1.0)
    assert ratio[1] == pytest.approx(0.5)
    assert ratio[2:] == pytest.approx(0.5**DAMP_MAX_HALVINGS)


def test_recovery_takes_several_steps_of_one_sign():
    p, s, m, table = _bench(True)
    s["big_sign"], s["damp_n"] = 1.0, DAMP_MAX_HALVINGS
    factors = [table_step_factor(s, 3.0) for _ in range(int(DAMP_MAX_HALVINGS / DAMP_RECOVERY))]
    assert factors == sorted(factors)  # growing back
    assert factors[0] < 0.5 and factors[-1] == pytest.approx(1.0)
    # a zero level leaves it as it is
    s["damp_n"] = 1.0
    assert table_step_factor(s, 0.0) == pytest.approx(0.5) and s["damp_n"] == 1.0


def test_the_fine_band_is_not_damped():
    small = [1e-4, -1e-4] * 3  # x = 0.1: inside the first threshold
    assert _steps(True, small) == _steps(False, small)
