"""Standstill R1 identification from any R2_hat(0) within +-40 %: its window follows the
flux build-up measured (kernels/estimators/mras.py, mras_r1_standstill), and it says when it
could not identify (log column ``R1_id_status_code``: 1 identified, 2 could not)."""

from __future__ import annotations

import pytest

from imdrive.config.scenario import Scenario
from imdrive.run.simulate import simulate


def _standstill(machine, r2_ratio, magnetise_s, r1_ratio=0.9):
    sc = Scenario.read(
        "sensorless",
        [
            f'machine.preset="{machine}"',
            "mras.R1_standstill=true",
            f"estimator.R1_ratio={r1_ratio}",
            f"estimator.R2_ratio={r2_ratio}",
            f"control.speed_ref_rpm={{initial=0,changes=[{{at={magnetise_s},to=300,over=1}}]}}",
            f"simulation.t_end_s={magnetise_s + 0.2}",
        ],
    )
    res = simulate(sc)
    return res["R1_hat_ohm"][-1] / sc.machine.R1_ohm, res["R1_id_status_code"][-1]


@pytest.mark.parametrize("machine", ["paper-table-iv", "aalto-2.2kw"])
@pytest.mark.parametrize("r2_ratio", [0.6, 0.7, 1.4])
def test_R1_is_identified_from_any_R2_hat_within_40_percent(machine, r2_ratio):
    # with the window at four of the controller's T2_hat, R2_hat(0) <= 0.76 R2 pushed it past
    # the 0.5 s magnetisation on Table IV and R1_hat stayed 10 % off without a word;
    # measured now: -0.9 % at 0.6, +0.4 % at 1.4 (the build-up left in the window)
    ratio, status = _standstill(machine, r2_ratio, 0.5)
    assert status == 1
    assert ratio == pytest.approx(1.0, abs=0.012)


@pytest.mark.parametrize("machine", ["paper-table-iv", "aalto-2.2kw"])
def test_too_short_a_magnetisation_says_it_could_not_identify(machine):
    # 0.2 s: the flux build-up (four rotor time constants) is not over on either machine
    ratio, status = _standstill(machine, 1.0, 0.2)
    assert status == 2
    assert ratio == pytest.approx(0.9, abs=1e-12)  # left as it was


def test_status_is_zero_without_a_standstill_run():
    sc = Scenario.read("sensorless", ["simulation.t_end_s=0.3"])
    assert simulate(sc)["R1_id_status_code"][-1] == 0.0
