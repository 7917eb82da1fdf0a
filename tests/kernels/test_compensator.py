"""The fuzzy R2 compensator inside the drive (paper §4, Fig. 1)."""

from __future__ import annotations

import numpy as np
import pytest

from imdrive.config.scenario import Scenario
from imdrive.fuzzy import fuzzy_table
from imdrive.kernels.compensator import (
    COMPENSATOR_PARAMS,
    COMPENSATOR_STATE,
    compensator_step,
    compensator_update,
)
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.records import new_record
from imdrive.run.simulate import build_arrays, simulate


class _Comp:
    """The compensator block's records (parameters, state, the controller's model) for one
    drive, and the table: a bench to drive it sample by sample."""

    def __init__(self, table="paper", period=10, R2_hat=0.9, lo=0.5, hi=1.5, gain=1e6, g_cr=0.001):
        self.p = new_record(
            COMPENSATOR_PARAMS,
            enabled=True,
            n=period,
            G_E=gain,
            G_DE=gain,
            G_CR=g_cr,
            R2_min=lo,
            R2_max=hi,
            average=True,
        )[0]
        self.s = np.zeros(1, dtype=COMPENSATOR_STATE)[0]
        self.m = new_record(MODEL_STATE, R2_hat=R2_hat)[0]
        self.table = fuzzy_table(table).astype(float)

    @property
    def R2_hat(self) -> float:
        return float(self.m["R2_hat"])

    def step(self, e_d0, t, k):
        compensator_step(self.p, self.s, self.m, self.table, e_d0, t, k)

    def update(self, E):
        compensator_update(self.p, self.s, self.m, self.table, E)


@pytest.mark.parametrize("source", ["paper", "rules"])
@pytest.mark.parametrize("e_d0, direction", [(-3e-6, -1), (3e-6, +1), (-20e-6, -1), (20e-6, +1)])
def test_constant_e_d0_moves_R2_hat_as_the_paper_rule_says(source, e_d0, direction):
    """e_d0 < 0 means R2_hat > R2 (paper §3): decrease R2_hat; e_d0 > 0: increase it."""
    comp = _Comp(source)
    table = comp.table
    r0 = comp.R2_hat
    history = []
    for k in range(1, 201):
        comp.step(e_d0, k * 1e-4, k)
        history.append(comp.R2_hat)
    steps = np.diff([r0, *history])
    assert np.all(np.sign(steps[steps != 0]) == direction)
    assert np.count_nonzero(steps) == 20  # one decision per 10 control periods
    # with DE = 0 the change per decision is G_CR times the table's E row at DE = 0
    level = 6 if abs(e_d0) > 5e-6 else 3
    expected = table[int(np.sign(e_d0)) * level + 6, 6] * 0.001
    assert steps[steps != 0][-1] == pytest.approx(expected)


def test_zero_e_d0_leaves_R2_hat_alone():
    comp = _Comp()
    for k in range(1, 101):
        comp.step(1e-7, k * 1e-4, k)  # inside the dead zone |E| <= 0.25e-6
    assert comp.R2_hat == 0.9


@pytest.mark.parametrize("e_d0, bound", [(-1e-3, 0.5), (1e-3, 1.5)])
def test_clamps_hold(e_d0, bound):
    comp = _Comp(g_cr=0.01)
    for k in range(1, 5001):
        comp.step(e_d0, k * 1e-4, k)
        assert 0.5 <= comp.R2_hat <= 1.5
    assert comp.R2_hat == bound


def test_change_of_error_enters_through_DE():
    """A growing negative error decreases R2_hat faster than a shrinking one (Table III)."""
    comp = _Comp()
    table = comp.table
    comp.update(-2e-6)  # first sample: DE = 0
    before = comp.R2_hat
    # E = -5.5 -> level -6; DE = -3.5 -> level -4; table[-6, -4] = -5
    comp.update(-5.5e-6)
    assert comp.R2_hat - before == pytest.approx(table[0, 2] * 0.001)
    before = comp.R2_hat
    # E = -2 -> level -3 (-3 < x <= -2); DE = +3.5 -> level 4; table[-3, 4] = 0
    comp.update(-2e-6)
    assert comp.R2_hat - before == pytest.approx(table[3, 10] * 0.001)
    assert table[0, 2] < table[3, 10]


def test_compensator_acts_only_after_enable_time():
    sc = Scenario.read(
        "sensorless-detuned",
        [
            "compensator.enabled=true",
            "compensator.t_on_s=2.5",
            "simulation.t_end_s=3.0",
            "simulation.log_every=1",
        ],
    )
    res = simulate(sc)
    r2 = res["R2_hat_ohm"]
    t = res.time_s
    assert np.all(r2[t < 2.5] == 0.9792)
    changes = t[1:][np.diff(r2) != 0]
    assert len(changes) > 0
    # decisions only at multiples of the 10 ms compensator period (logged at that sample)
    assert np.allclose(np.round(changes / 0.01) * 0.01, changes, atol=1e-9)
    assert changes[0] >= 2.5


def test_mras_and_slip_use_the_updated_estimate_at_once():
    """A compensator clamped to R2_hat = 0.9 ohm gives the same drive as R2_hat = 0.9 from t=0.

    Both the MRAS's adjustable model and the slip calculation must read the new value, or the
    steady-state speed (the detuning law) would differ.
    """
    common = ["simulation.t_end_s=4.0", "control.speed_ref_rpm=600"]
    fixed = simulate(Scenario.read("sensorless", [*common, "estimator.R2_ohm=0.9"]))
    clamped = simulate(
        Scenario.read(
            "sensorless",
            [
                *common,
                "estimator.R2_ohm=0.7",
                "compensator.enabled=true",
                "compensator.t_on_s=0.0",
                "compensator.R2_min_ohm=0.9",
                "compensator.R2_max_ohm=0.90001",
                "compensator.G_CR_ohm=1.0",
            ],
        )
    )
    w_f = fixed.window(3.5)
    w_c = clamped.window(3.5)
    assert np.all(np.abs(w_c["R2_hat_ohm"] - 0.9) <= 1e-5)
    dev_f = np.mean(w_f["speed_rpm"] - w_f["speed_ref_rpm"])
    dev_c = np.mean(w_c["speed_rpm"] - w_c["speed_ref_rpm"])
    assert dev_f > 1.0  # R2_hat = 0.9 > 0.816: the drive runs fast
    assert dev_c == pytest.approx(dev_f, rel=1e-3)


def test_compensator_settings_reach_the_kernel():
    sc = Scenario.read(
        "sensorless-detuned",
        ["compensator.enabled=true", "compensator.table=rules"],
    )
    a = build_arrays(sc)
    assert a.params.comp["n"][0] == 100  # 10 ms without the injection
    assert a.params.comp["R2_min"][0] == pytest.approx(0.5 * 0.9792)
    assert np.array_equal(a.params.tables[0], fuzzy_table("rules").astype(float))
