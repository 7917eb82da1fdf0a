"""Regenerating at low speed by stator frequency (imdrive.studies.zero_frequency): the speed
references put each machine at the asked stator frequency, and a reduced run reproduces the
stored runs of docs/machine-envelope.md's table."""

from __future__ import annotations

import math
import warnings

import pandas as pd
import pytest

from imdrive.config.machine import rated_point
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigWarning
from imdrive.studies import machines as envelope
from imdrive.studies import zero_frequency as study
from imdrive.studies.doctable import DOCS


def _sensorless(machine):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        return Scenario.read("sensorless", [f'machine.preset="{machine}"'])


@pytest.mark.parametrize("machine", study.MACHINES)
def test_speed_reference_runs_at_the_stator_frequency(machine):
    sc = _sensorless(machine)
    rp = rated_point(sc.machine)
    T = -rp.torque_Nm
    speeds = [study.speed_for_stator_frequency(sc, f, T) for f in study.F_S_HZ]
    for f, n in zip(study.F_S_HZ, speeds, strict=True):
        assert envelope.stator_frequency_Hz(sc, n, T, 1.0) == pytest.approx(f, abs=1e-6)
    # the slip fixed by the torque, the speed moves by 60/n_p rpm per hertz (friction aside)
    step = (speeds[-1] - speeds[0]) / (study.F_S_HZ[-1] - study.F_S_HZ[0])
    assert step == pytest.approx(60.0 / sc.machine.pole_pairs, rel=0.01)
    # regenerating, f_s = 0 is below the synchronous speed of the slip: a positive speed
    # equal to the rated-torque slip at the rated flux (w_sl = R2 T / (1.5 n_p psi^2))
    m = sc.machine
    w_sl = m.R2_ohm * rp.torque_Nm / (1.5 * m.pole_pairs * m.rated_flux_Wb**2)
    n0 = study.speed_for_stator_frequency(sc, 0.0, T)
    assert n0 == pytest.approx(w_sl / m.pole_pairs * 30 / math.pi, rel=0.02)


def test_a_frequency_no_speed_reaches_is_refused():
    sc = _sensorless("paper-table-iv")
    with pytest.raises(ValueError, match="f_s_Hz"):
        study.speed_for_stator_frequency(sc, 500.0, -rated_point(sc.machine).torque_Nm)


def test_the_stored_runs_cover_the_study():
    t = pd.read_csv(DOCS / "data" / "zero_frequency.csv")
    n = len(study.F_S_HZ) * len(study.R2_RATIOS) * len(study.DRIVES)
    assert (t.groupby("machine").size() == n).all()
    assert set(t["machine"]) == set(study.MACHINES)
    assert set(t["f_s_target_Hz"]) == set(study.F_S_HZ)
    # each run is at the frequency it is filed under
    assert (t["f_s_R2_Hz"] - t["f_s_target_Hz"]).abs().max() < 1e-6


def test_the_observer_on_the_identified_R1_loses_no_run():
    """``injection-robust`` on the adaptive observer, its R1 from the drive's standstill test
    (R1_hat(0) = 1.1 R1): no loss of control at any stator frequency from -0.5 to 2 Hz,
    regenerating the rated torque, on the four machines. Before the test served every
    estimator the observer ran on 1.1 R1 and lost 81 of these 84 runs; the MRAS loses 19."""
    t = pd.read_csv(DOCS / "data" / "zero_frequency.csv")
    afo = t[t["drive"] == "injection-robust-afo"]
    assert len(afo) == len(study.MACHINES) * len(study.F_S_HZ) * len(study.R2_RATIOS)
    assert not afo["lost_control"].any()
    assert (afo["verdict"] != "lost").all()


@pytest.mark.slow
def test_reduced_run_reproduces_the_stored_runs():
    t = study.run(["krause-500hp"], frequencies=(0.5,), ratios=(1.2,))
    stored = pd.read_csv(DOCS / "data" / "zero_frequency.csv")
    keys = ["machine", "drive", "f_s_target_Hz", "R2_ratio"]
    both = t.merge(stored, on=keys, suffixes=("", "_stored"), validate="one_to_one")
    assert len(both) == len(study.DRIVES)
    for _, row in both.iterrows():
        assert row["verdict"] == row["verdict_stored"]
        for col in ("speed_error_rpm", "R2_error_pct"):
            assert float(row[col]) == pytest.approx(float(row[col + "_stored"]), rel=1e-6), (
                f"{row[keys].to_dict()} {col}: run "
                "'python -m imdrive.studies.doctables --run zero-frequency'"
            )


def test_the_observer_drive_is_judged_by_its_R2_hat_as_injection_robust_is():
    """``injection-robust-afo`` tracks R2: its verdict is R2_hat's (within 2 % and the speed
    within tolerance), not the detuning law of a drive that holds R2_hat, which marked its
    tracked runs "not converged" (the speed error of a tracked R2 is not the law's)."""
    from imdrive.studies import machines

    row = {
        "status": 0, "lost_control": False, "rated_speed_rpm": 1720.9, "R2_error_pct": -0.1,
        "R2_error_window_pct": -0.1, "speed_error_rpm": 0.05, "detuning_law_rpm": 15.0,
    }  # fmt: skip
    for drive in ("injection-robust", "injection-robust-afo"):
        assert machines.tracks_r2(drive)
        assert machines.verdict({**row, "drive": drive}) == "converged"
        assert machines.verdict({**row, "drive": drive, "R2_error_pct": 3.0}) == "not converged"
    assert not machines.tracks_r2("sensorless-afo")
    assert machines.verdict({**row, "drive": "sensorless-afo"}) == "not converged"
    stored = pd.read_csv(DOCS / "data" / "zero_frequency.csv")
    afo = stored[stored["drive"] == "injection-robust-afo"]
    assert afo["detuning_law_rpm"].isna().all()
    assert (afo["verdict"] == afo.apply(machines.verdict, axis=1)).all()


def _r1_table():
    return pd.read_csv(DOCS / "data" / "zero_frequency_R1.csv")


def test_near_zero_stator_frequency_R2_hat_follows_an_R1_hat_error_a_hundredfold():
    """The R1-sensitivity table (docs/machine-envelope.md): at 0 Hz an R1_hat error of 0.1 %
    moves R2_hat's end by more than 5 % on every machine (R1 and R2 cannot be told apart
    there), where at +2 Hz it moves it by less than 1 % on Table IV and the Aalto machine; with
    R1_hat = R1 the observer drive ends within 2 % at 0 Hz on all three."""
    t = _r1_table()
    assert set(t["machine"]) == set(study.R1_MACHINES)
    assert set(t["f_s_target_Hz"]) == set(study.R1_F_S_HZ)
    assert set(t["R1_ratio"]) == set(study.R1_RATIOS)
    for m, g in t.groupby("machine"):
        at0 = g[g["f_s_target_Hz"] == 0.0].set_index("R1_ratio")["R2_error_pct"]
        assert abs(at0[1.0]) < 2.0, m
        assert max(abs(at0[0.999] - at0[1.0]), abs(at0[1.001] - at0[1.0])) > 5.0, m
    for m in ("paper-table-iv", "aalto-2.2kw"):
        g = t[(t["machine"] == m) & (t["f_s_target_Hz"] == 2.0)]
        assert g["R2_error_pct"].abs().max() < 1.0, m


@pytest.mark.slow
def test_reduced_run_reproduces_the_stored_R1_sensitivity():
    t = study.r1_sensitivity(["paper-table-iv"], frequencies=(0.0,), ratios=(0.999, 1.0))
    stored = _r1_table()
    keys = ["machine", "f_s_target_Hz", "R1_ratio"]
    both = t.merge(stored, on=keys, suffixes=("", "_stored"), validate="one_to_one")
    assert len(both) == 2
    for _, row in both.iterrows():
        assert float(row["R2_error_pct"]) == pytest.approx(
            float(row["R2_error_pct_stored"]), rel=1e-6
        ), "run 'python -m imdrive.studies.doctables --run zero-frequency-R1'"
