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


def test_the_observer_on_the_identified_R1_loses_one_run_near_zero():
    """``injection-robust`` on the adaptive observer (its estimator since 2026-11-30, chosen by
    this count), its R1 from the drive's standstill test
    (R1_hat(0) = 1.1 R1), regenerating the rated torque from -0.5 to 2 Hz on the four machines:
    one of the 84 runs loses control (Krause 500 hp at 0 Hz from 0.8 R2, R2_hat 54 % low: R2
    is not observable there; until the injection's side bands were kept above the detection
    filter's corner, 2026-11-30, the lost run was at +0.25 Hz from 1.2 R2), and its verdict
    says it ran near zero stator frequency; the MRAS loses 15. Before the test served every
    estimator the observer ran on 1.1 R1 and lost 81 of these runs; with its constant gain
    (before 2026-11-29) none, but it converged in 42 where it did in 46 then (71 now)."""
    t = pd.read_csv(DOCS / "data" / "zero_frequency.csv")
    afo = t[t["drive"] == "injection-robust"]
    assert len(afo) == len(study.MACHINES) * len(study.F_S_HZ) * len(study.R2_RATIOS)
    lost = afo[afo["lost_control"]]
    assert len(lost) <= 1
    assert (lost["f_s_target_Hz"].abs() <= 0.5).all()
    assert lost["verdict_text"].str.contains("near zero stator frequency").all()
    mras = t[t["drive"] == "injection-robust-mras"]
    assert mras["lost_control"].sum() >= 10 * max(len(lost), 1)


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


def test_the_recommended_drive_ends_within_5_percent_and_loses_no_run():
    """``injection-robust`` over the study (four machines, -0.5 ... +2 Hz, R2_hat(0) 0.8, 1.0
    and 1.2 R2): every run ends with R2_hat within 5 %, none loses control, and a run outside
    "converged" says it ran near zero stator frequency. Krause 500 hp at +1 Hz ended -7.0 and
    -6.6 % while the law divided by the unfiltered sensitivity; the detection's filter leaves
    0.15-0.17 of it there (kernels/r2_kalman.py, law_response, 2026-12-01)."""
    t = pd.read_csv(DOCS / "data" / "zero_frequency.csv")
    rec = t[t["drive"] == "injection-robust"]
    assert len(rec) == 84
    assert (rec["R2_error_pct"].abs() <= 5.0).all(), rec.loc[rec["R2_error_pct"].abs() > 5]
    assert not rec["lost_control"].any()
    miss = rec[rec["verdict"] != "converged"]
    assert miss["verdict_text"].str.contains("near zero stator frequency").all()
    assert len(miss) <= 2


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


def test_the_MRAS_drives_R2_hat_follows_R1_hat_as_the_voltage_model_says():
    """The R1-sensitivity table (docs/machine-envelope.md): on the MRAS drive a 1 % R1_hat
    error moves R2_hat's end by eq. (1)'s ``g`` to within a factor 2.5 at 2 Hz on every
    machine and at 1 Hz on all but Krause 50 hp (where the MRAS's correction is weakest, 6.1
    against 1.14); with R1_hat = R1 it ends within 1 % from +0.5 Hz up."""
    t = _r1_table()
    assert set(t["machine"]) == set(study.R1_MACHINES)
    assert set(t["f_s_target_Hz"]) == set(study.R1_F_S_HZ)
    assert set(t["R1_ratio"]) == set(study.R1_RATIOS)
    mras = t[t["estimator"] == "mras"]
    for (m, f), g in mras.groupby(["machine", "f_s_target_Hz"]):
        if f == 2.0 or (f == 1.0 and m != "krause-50hp"):
            ratio = study.moved_pct(g) / float(g["g_predicted"].iloc[0])
            assert 1 / 2.5 < ratio < 2.5, (m, f, ratio)
    exact = mras[(mras["R1_ratio"] == 1.0) & (mras["f_s_target_Hz"] >= 0.5)]
    assert exact["R2_error_pct"].abs().max() < 1.0


def test_the_observers_R2_hat_follows_R1_hat_further_than_the_voltage_model_says():
    """On the observer's drive a 1 % R1_hat error moves R2_hat by more than 5 % at 0 Hz on
    Table IV and Krause 50 hp (10.7 and 6.8 % per %), and at 2 Hz by more than twice eq.
    (1)'s ``g`` on Krause 500 hp and the Aalto machine (3.5 and 5.7 % per % against g = 0.63
    and 2.06): its detection's current model runs at the observer's speed, which R1_hat moves
    too. Krause 50 hp at 2 Hz follows eq. (1) since the injection's schedule keeps its side
    bands off DC (0.63 % per % against g = 0.57; 4.8 before, where the injection read the
    detuned drive's oscillation, kernels/gating.py). On the Aalto machine at 0 Hz the R1
    error swings the observer's speed 24-27 rpm, and the law holds R2_hat 44-75 % of the
    time. (With the observer's constant gain: 17-78 % at 0 Hz, over 2 g at 2 Hz on three
    machines.)"""
    afo = _r1_table().query("estimator == 'afo'")
    zero = afo[afo["f_s_target_Hz"] == 0.0]
    moved0 = {m: study.moved_pct(g) for m, g in zero.groupby("machine")}
    assert moved0["paper-table-iv"] > 5.0 and moved0["krause-50hp"] > 5.0
    aalto = zero[(zero["machine"] == "aalto-2.2kw") & (zero["R1_ratio"] != 1.0)]
    assert (aalto["R2_held_pct"] > 40.0).all()
    at2 = afo[afo["f_s_target_Hz"] == 2.0]
    ratio = {m: study.moved_pct(g) / g["g_predicted"].iloc[0] for m, g in at2.groupby("machine")}
    assert ratio["krause-500hp"] > 2.0 and ratio["aalto-2.2kw"] > 2.0
    assert ratio["krause-50hp"] < 1.5


@pytest.mark.slow
def test_reduced_run_reproduces_the_stored_R1_sensitivity():
    t = study.r1_sensitivity(
        ["paper-table-iv"], frequencies=(1.0,), ratios=(0.99, 1.0), estimators=("mras",)
    )
    stored = _r1_table()
    keys = ["machine", "f_s_target_Hz", "R1_ratio", "estimator"]
    both = t.merge(stored, on=keys, suffixes=("", "_stored"), validate="one_to_one")
    assert len(both) == 2
    for _, row in both.iterrows():
        assert float(row["R2_error_pct"]) == pytest.approx(
            float(row["R2_error_pct_stored"]), rel=1e-6
        ), "run 'python -m imdrive.studies.doctables --run zero-frequency-R1'"


@pytest.mark.parametrize("drive, n_min", [("injection-robust", 2), ("injection-robust-mras", 30)])
def test_the_recommended_drives_misses_near_zero_are_where_R2_is_weakly_observable(drive, n_min):
    """Every run of ``injection-robust`` outside "converged" at -0.5 ... +0.5 Hz is at a point
    where eq. (1) puts a 1 % R1_hat error beyond the 2 % tolerance (its status says so), on
    the observer (the preset since 2026-11-30: 2 such runs since the schedule keeps its side
    bands off DC, 3 since the Kalman law carries its
    measurement's variance through to R2, 4 since its injection's frequency follows the
    detection's modelled response regenerating below the rated slip frequency, both
    2026-12-01; 8 before, 23 before its side bands were kept above the detection filter's
    corner) and on the MRAS (33)."""
    t = pd.read_csv(DOCS / "data" / "zero_frequency.csv")
    miss = t[(t["drive"] == drive) & (t["verdict"] != "converged")]
    near = miss[miss["f_s_target_Hz"].abs() <= 0.5]
    assert len(near) >= n_min
    g = [
        study.predicted_sensitivity(m, f)
        for m, f in zip(near["machine"], near["f_s_target_Hz"], strict=True)
    ]
    assert all(x * 0.01 > 0.02 for x in g)
