"""Standstill R1 identification from any R2_hat(0) within +-40 %: its window follows the
flux build-up measured (kernels/estimators/mras_standstill.py, mras_r1_standstill), and it says
when it could not identify (log column ``R1_id_status_code``: 1 identified, 2 could not). The
one-level test (``mras.R1_standstill_levels = 1``); two levels: test_r1_two_levels.py."""

from __future__ import annotations

import pytest

from imdrive.config.scenario import Scenario
from imdrive.run.simulate import simulate


def _standstill(machine, r2_ratio, magnetise_s, r1_ratio=0.9):
    """R1_hat/R1 and the status when the speed reference leaves zero at ``magnetise_s``, the
    start not waiting for the window (``mras.R1_standstill_hold_T2 = 0``;
    test_r1_standstill_wait.py has the wait) nor premagnetising longer by itself
    (``control.premagnetise_T2 = 0``), with no load (the preset's is per-unit of the
    machine: its rated load at 2 s pulled Geyer's 3.3 kV machine away from standstill before
    its 5 T2 were over; 12 N m on every machine before)."""
    sc = Scenario.read(
        "sensorless",
        [
            f'machine.preset="{machine}"',
            "mras.R1_standstill=true",
            "mras.R1_standstill_levels=1",
            "mras.R1_standstill_hold_T2=0",
            "control.premagnetise_T2=0",
            "load.torque_Nm=0",
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
    # the 0.5 s magnetisation on Table IV and R1_hat stayed 10 % off without a word.
    # The build-up left in the window is fitted as the decay at the T2 measured: with the
    # controller's current-model build-up (T2_hat's shape) R1_hat was -0.9 % off from 0.6 R2
    # and +0.4 % from 1.4 R2 on Table IV; measured now within 0.05 %
    ratio, status = _standstill(machine, r2_ratio, 0.5)
    assert status == 1
    assert ratio == pytest.approx(1.0, abs=0.002)


@pytest.mark.parametrize("machine", ["paper-table-iv", "krause-50hp", "geyer-3.3kv"])
def test_R1_hat_does_not_carry_the_error_of_R2_hat(machine):
    # a linear rotor circuit under a constant flux current builds its flux up as one
    # exponential at the plant's T2, whatever the controller's R2_hat: the identified R1 is
    # the same from R2_hat(0) = 0.6 and 1.4 R2. With the build-up's regressor at T2_hat's
    # shape the two differed by 3.1 % of R1 on Krause 50 hp (-1.7 / +1.4 %) and 1.4 % on
    # Table IV; measured now 0.01 %. The magnetisation is the machine's four T2 and a window
    T2 = Scenario.read("sensorless", [f'machine.preset="{machine}"']).machine.T2_s
    low, s_low = _standstill(machine, 0.6, 5.0 * T2)
    high, s_high = _standstill(machine, 1.4, 5.0 * T2)
    assert s_low == s_high == 1
    assert high - low == pytest.approx(0.0, abs=0.001)
    assert low == pytest.approx(1.0, abs=0.001)


@pytest.mark.parametrize("machine", ["paper-table-iv", "aalto-2.2kw"])
def test_too_short_a_magnetisation_says_it_could_not_identify(machine):
    # 0.2 s: the flux build-up (four rotor time constants) is not over on either machine
    ratio, status = _standstill(machine, 1.0, 0.2)
    assert status == 2
    assert ratio == pytest.approx(0.9, abs=1e-12)  # left as it was


def test_status_is_zero_without_a_standstill_run():
    sc = Scenario.read("sensorless", ["simulation.t_end_s=0.3"])
    assert simulate(sc)["R1_id_status_code"][-1] == 0.0


def _realistic_standstill(machine, r2_ratio, magnetise_s):
    """The uncommissioned realistic drive (imdrive.studies.realistic: the switching bridge with
    2 us dead time compensated as 1.6 us, 1 V device drops, a one-period delay, sensor errors,
    a saturating machine) magnetising at standstill, the speed reference leaving zero at
    ``magnetise_s``: R1_hat and the identification's status when it does."""
    from imdrive.studies.realistic import DRIVES, read

    sc = read(
        "injection-fig5",
        [
            *DRIVES["realistic (all)"],
            f'machine.preset="{machine}"',
            "mras.R1_standstill_levels=1",
            # Schauder's error, as measured: at this standstill the speed estimate wanders
            # and the rotated error moves with it (not investigated: a lead)
            "mras.regeneration_angle_deg=0",
            f"estimator.R2_ratio={r2_ratio}",
            f"control.speed_ref_rpm={{initial=0,changes=[{{at={magnetise_s},to=300,over=1}}]}}",
            f"simulation.t_end_s={magnetise_s + 0.02}",
            "output.figures=false",
        ],
        "realistic (all)",
    )
    res = simulate(sc)
    return res["R1_hat_ohm"][-1] / sc.machine.R1_ohm, res["R1_id_status_code"][-1]


@pytest.mark.parametrize(
    ("machine", "r2_ratio"),
    [
        ("paper-table-iv", 0.6),
        ("paper-table-iv", 1.2),
        ("aalto-2.2kw", 0.6),
        ("aalto-2.2kw", 1.4),
    ],
)
def test_on_a_saturating_machine_the_window_follows_the_decay_measured(machine, r2_ratio):
    # a saturating machine's build-up is slow at first and fast at the end: at 3.5 times the
    # mean of the block-wise T2 (0.117 s against 0.087 s on Table IV) the window opened too late
    # for the 0.5 s magnetisation from 1.2 R2 on Table IV and from every R2_hat(0) on the Aalto
    # machine (status 2, R1_hat left). Identified now, and to what it is from R2_hat(0) = R2:
    # R1 plus the bridge's residual at the magnetising current. Since the drive holds still
    # through the test (2026-11-30) its current stays on the alpha axis, where the bridge's
    # error is largest: on Table IV that is above the test's clamp, 2 R1, from every R2_hat(0)
    # (1.873-1.883 R1 while the frame wandered with the speed estimate), and the case checks
    # only the identification; Aalto 1.2645 from R2, 1.2678 from 0.6 R2 and 1.2653 from 1.4 R2
    # (1.224, 1.241 and 1.188 while the rotor turned: from 1.4 R2 2.9 % apart, an xfail)
    ratio, status = _realistic_standstill(machine, r2_ratio, 0.5)
    assert status == 1
    exact, exact_status = _realistic_standstill(machine, 1.0, 0.5)
    assert exact_status == 1
    assert ratio == pytest.approx(exact, rel=0.02)
    if machine == "aalto-2.2kw":  # inside the clamps: the agreement means something
        assert 1.0 < ratio < 1.99


def test_a_run_that_could_not_identify_says_so_in_its_status():
    from imdrive import simulate_batch
    from imdrive.run.status import R1_NOT_IDENTIFIED

    sc = Scenario.read(
        "sensorless",
        [
            "mras.R1_standstill=true",
            "mras.R1_standstill_levels=1",
            "mras.R1_standstill_hold_T2=0",  # the start does not wait for the window
            "control.premagnetise_T2=0",  # nor for 3 T2_hat (0.26 s)
            "load.torque_Nm=0",  # the preset's load step at t_end: its settling is not the point
            "control.speed_ref_rpm={initial=0,changes=[{at=0.2,to=300,over=1}]}",
            "simulation.t_end_s=2.0",
        ],
    )
    res = simulate(sc)
    assert res["R1_id_status_code"][-1] == 2
    m = res.metrics()
    assert m["R1_id_status"] == 2
    assert m["verdict_text"].endswith(R1_NOT_IDENTIFIED)
    row = simulate_batch([sc]).metrics.iloc[0]  # the batch reads it from the final state
    assert row.verdict_text == m["verdict_text"]
    ok = simulate(
        sc.with_overrides(["control.speed_ref_rpm={initial=0,changes=[{at=0.5,to=300,over=1}]}"])
    )
    assert R1_NOT_IDENTIFIED not in ok.metrics()["verdict_text"]
