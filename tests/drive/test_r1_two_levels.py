"""Standstill R1 at two current levels on the dead-time bridge (``mras.R1_standstill_levels =
2``, kernels/estimators/mras_standstill.py): R1 = du/di cancels the residual the dead-time
compensation leaves (2 us compensated as 1.6 us, the envelope's bridge), which one level reads
as resistance; the speed reference waits for the test; the residual starts the compensation's
online scale, which at 20 rpm never adapts, and with both the bridge's 20 rpm cells run."""

from __future__ import annotations

import numpy as np
import pytest

from imdrive.config.scenario import Scenario
from imdrive.run.simulate import simulate

BRIDGE = [
    'inverter.model="switching"',
    "inverter.dead_time_s=2e-6",
    'control.dead_time_compensation="feedforward"',
    "control.dead_time_compensation_s=1.6e-6",
]


def _standstill(machine, r2_ratio, levels=2, magnetise_T2=None):
    """injection-robust on the bridge magnetising from R1_hat(0) = 0.9 R1, the speed reference
    leaving zero at ``magnetise_T2`` rotor time constants (0.5 s if None): R1_hat / R1, the
    identification's status, and how long the reference waited for the test, in T2."""
    T2 = Scenario.read("injection-robust", [f'machine.preset="{machine}"']).machine.T2_s
    mag = 0.5 if magnetise_T2 is None else magnetise_T2 * T2
    sc = Scenario.read(
        "injection-robust",
        [
            f'machine.preset="{machine}"',
            f"mras.R1_standstill_levels={levels}",
            f"estimator.R2_ratio={r2_ratio}",
            "estimator.R1_ratio=0.9",
            f"control.speed_ref_rpm={{initial=0,changes=[{{at={mag},to=300,over=1}}]}}",
            f"simulation.t_end_s={mag + 8 * T2}",
            *BRIDGE,
        ],
    )
    res = simulate(sc)
    moved = np.nonzero(res["speed_ref_rpm"] != 0.0)[0]
    assert moved.size, "the speed reference still waited at the end"
    waited = (res["time_s"][moved[0]] - mag) / T2
    return res["R1_hat_ohm"][-1] / sc.machine.R1_ohm, res["R1_id_status_code"][-1], waited


@pytest.mark.parametrize("machine", ["paper-table-iv", "aalto-2.2kw"])
@pytest.mark.parametrize("r2_ratio", [0.6, 1.4])
def test_two_levels_identify_R1_through_the_dead_time_residual(machine, r2_ratio):
    # measured 0.999-1.000 R1; the reference waited 2.2-4.2 T2 past the 0.5 s magnetisation
    ratio, status, waited = _standstill(machine, r2_ratio)
    assert status == 1
    assert ratio == pytest.approx(1.0, abs=0.005)
    assert 0.0 < waited < 6.0


@pytest.mark.parametrize(("machine", "bias"), [("paper-table-iv", 1.10), ("aalto-2.2kw", 1.04)])
def test_one_level_reads_the_residual_as_resistance(machine, bias):
    # the same bridge, one level: R1 plus the residual over the magnetising current (measured
    # 1.13 R1 on Table IV, 1.055 on the Aalto machine), and no wait
    ratio, status, waited = _standstill(machine, 1.0, levels=1)
    assert status == 1
    assert ratio > bias
    assert waited < 0.2


@pytest.mark.parametrize("r2_ratio", [0.6, 1.3, 1.4])
def test_krause_50hp_in_the_machine_envelopes_magnetisation(r2_ratio):
    # the machine envelope magnetises for 4 T2: one level's window did not open there from
    # R2_hat(0) = 1.2-1.3 R2 (R1_hat left, status 2); the reference now waits for both levels
    ratio, status, waited = _standstill("krause-50hp", r2_ratio, magnetise_T2=4.0)
    assert status == 1
    assert ratio == pytest.approx(1.0, abs=0.005)
    assert waited < 8.0


@pytest.mark.slow
@pytest.mark.parametrize(("levels", "ok"), [(1, False), (2, True)])
def test_the_bridge_at_20_rpm_runs_with_the_residual_identified(levels, ok):
    # an envelope-full cell (+20 rpm, half the available torque, R2_hat(0) = R2, R1_hat(0) =
    # 0.9 R1, dead-time bridge): with one level R1_hat holds the residual and the MRAS's
    # reference model is wrong at the load's current (lost control, measured); two levels
    # put R1_hat at R1 and the compensation's scale where it leaves no residual
    from imdrive.sweep import load_sweep

    sw = load_sweep("envelope-full")
    want = dict(
        speed_pu=0.0116, load_pu_available=0.5, R2_ratio=1.0, R1_ratio=0.9,
        thermal="constant", inverter="bridge",
    )  # fmt: skip
    sc = sw.scenario_for(tuple(want[a.name] for a in sw.axes)).with_overrides(
        [f"mras.R1_standstill_levels={levels}", "simulation.log_every=1000"]
    )
    m = simulate(sc).metrics()
    assert (m["verdict"] == "ok") == ok, m["verdict_text"]
