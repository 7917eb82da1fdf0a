"""The model-based R2 law (kernels/r2_kalman.py) on hand-made records: the measurement inverts
the analytic sensitivity, the steady gains are those of the discrete algebraic Riccati
equation (scipy's solver), a ramp of R2 is followed with no steady lag (the drift state takes
its slope), a gated window grows the covariance and moves nothing; and in the drive, from
R2_hat(0) = 0.8 and 1.2 R2 on three machines at points of four kinds (half speed, low speed at
rated load, regenerating at 0.1 speed, rated speed), R2_hat ends within 1 % with the MRAS and
within 1.5 % with the AFO (through the detector's own flux error)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg

import imdrive
from imdrive.config.rated import rated_point
from imdrive.kernels.compensator import COMPENSATOR_PARAMS, COMPENSATOR_STATE
from imdrive.kernels.detection_response import responses
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.r2_kalman import (
    NOT_OBSERVABLE,
    kalman_decision,
    kalman_hold,
    kalman_update,
    law_response,
    relative_error,
)
from imdrive.kernels.records import new_record
from imdrive.kernels.sensitivity import in_phase_sensitivity

R2_0 = 0.8  # ohm
M, LL2 = 0.07, 0.002  # H
AMP, F_INJ = 0.5, 2.0  # A, Hz
T = 1.0 / F_INJ  # decision period, s
NOISE, DRIFT, PRIOR = 0.03, 0.01, 0.3


def _records(R2_hat=R2_0):
    p = new_record(
        COMPENSATOR_PARAMS, kf=True, kf_r=NOISE, kf_q=DRIFT, kf_p0=PRIOR, kf_R2=R2_0, kf_T=T,
        inj_amp=AMP, inj_freq=F_INJ, R2_min=0.1 * R2_0, R2_max=10 * R2_0,
    )[0]  # fmt: skip
    s = np.zeros(1, dtype=COMPENSATOR_STATE)[0]
    m = new_record(MODEL_STATE, R2_hat=R2_hat, M_hat=M, Ll2_hat=LL2)[0]
    return p, s, m


def _detected(m, R2_true):
    """The window's detected error the linear model predicts: ``-M a S r``."""
    r = m["R2_hat"] / R2_true - 1.0
    S = in_phase_sensitivity(2 * math.pi * F_INJ, (M + LL2) / m["R2_hat"])
    return -M * AMP * S * r


def test_the_measurement_inverts_the_analytic_sensitivity():
    p, s, m = _records(R2_hat=0.88)
    for r in (-0.2, -0.01, 0.0, 0.05, 0.3):
        S = in_phase_sensitivity(2 * math.pi * F_INJ, (M + LL2) / 0.88)
        assert relative_error(p, s, m, -M * AMP * S * r) == pytest.approx(r, abs=1e-12)
    s["inj_back"] = 0.5  # the voltage headroom halved the amplitude: the same E is twice r
    assert relative_error(p, s, m, -M * AMP * S * 0.1) == pytest.approx(0.2)


def _windowed(f_e_Hz, w_sl=0.0, coupled=False, wc=15.0):
    """Records of a gated law (the window's means known) at the stator frequency ``f_e_Hz``
    with the comparison filter's corner ``wc`` (rad/s); ``coupled``: the detection's speed
    path off over the window, regenerating below the rated slip."""
    p, s, m = _records()
    p["gate"], p["det"], p["cpl_wc"], p["det_wmin"] = True, True, wc, abs(w_sl)
    s["we_mean"], s["w_sl_mean"] = 2 * math.pi * f_e_Hz, w_sl
    s["rl_share"] = 1.0 if coupled else 0.0
    return p, s, m


def test_the_law_divides_by_the_response_where_both_side_bands_are_under_the_corner():
    """Where ``|w_e| + w_i`` is under the detection filter's corner (both side bands of the
    injection under it) the law divides by the response detection_response.py gives through
    the filter, and the measurement inverts that (Krause 500 hp at +1 Hz with its 0.19 Hz
    injection: 0.17 S, the detection measured 0.03 S; dividing by S, R2_hat took over 100 s to
    close 20 %). Elsewhere it keeps S, though the model may give less (Table IV at 0.1 of the
    rated speed: 0.5-0.85 S, the detection measured 0.92-1.06 S)."""
    w_i, T2 = 2 * math.pi * F_INJ, (M + LL2) / R2_0
    S = in_phase_sensitivity(w_i, T2)
    p, s, m = _windowed(0.2)  # 2 pi (0.2 + 2) Hz = 13.8 rad/s, under 15
    v, S_law = law_response(p, s, m)
    r0, _ = responses(w_i, T2, 0.0, 2 * math.pi * 0.2, 15.0)
    assert S_law == pytest.approx(S) and v == pytest.approx(r0) and 0.0 < v < 0.6 * S
    assert relative_error(p, s, m, -M * AMP * v * 0.1) == pytest.approx(0.1)
    for f_e in (1.0, 5.0, 50.0):  # the upper side band above the corner: S
        p, s, m = _windowed(f_e)
        assert law_response(p, s, m) == (S_law, S_law)
    assert responses(w_i, T2, 0.0, 2 * math.pi * 5.0, 15.0)[0] < 0.8 * S
    p, s, m = _windowed(0.2)
    p["det"] = False  # the estimator hands its own flux error (the MRAS family): S
    assert law_response(p, s, m) == (S_law, S_law)


def test_a_window_whose_modelled_response_is_not_positive_is_held():
    """Injecting at 0.5 Hz (``x = w_i T2 = 0.28``) at 0.2 Hz of stator frequency, the filtered
    response is negative (-0.27 S): the window would read R2 with the wrong sign. It measures
    nothing: R2_hat stays, the covariance grows and the gating mask says why (bit
    :data:`NOT_OBSERVABLE`). Slip-coupled (the speed path off while regenerating below the
    rated slip), the law keeps ``S``, as measured (module docstring)."""
    p, s, m = _windowed(0.2)
    p["inj_freq"] = 0.5
    assert responses(2 * math.pi * 0.5, (M + LL2) / R2_0, 0.0, 2 * math.pi * 0.2, 15.0)[0] < 0
    assert law_response(p, s, m)[0] == 0.0
    kalman_update(p, s, m, 0.0, T)
    P00, R2 = s["kf_P00"], m["R2_hat"]
    kalman_decision(p, s, m, -M * AMP * 0.01)
    assert m["R2_hat"] == R2 and s["kf_P00"] > P00
    assert s["frozen"] == NOT_OBSERVABLE and not s["live"]
    p, s, m = _windowed(0.2, w_sl=-2 * math.pi * 2.0, coupled=True)
    p["inj_freq"] = 0.5
    v, S = law_response(p, s, m)
    assert v == S > 0.0
    kalman_decision(p, s, m, -M * AMP * 0.01)
    assert m["R2_hat"] != R2_0 and s["live"]


def test_a_weak_response_reads_the_detections_noise_larger():
    """The detection's noise reads as ``r`` through ``1/v``: where the filtered response is a
    fraction of ``S`` (0.47 S at 0.2 Hz of stator frequency here) the measurement's standard
    deviation is ``kf_r S/v``, and the steady covariance is the Riccati equation's with it."""
    p, s, m = _windowed(0.2)
    v, S = law_response(p, s, m)
    assert 0.3 < v / S < 0.6
    for _ in range(400):
        kalman_update(p, s, m, 0.0, T)
    P_post = np.array([[s["kf_P00"], s["kf_P01"]], [s["kf_P01"], s["kf_P11"]]])
    F = np.array([[1.0, T], [0.0, 1.0]])
    Q = (DRIFT * R2_0) ** 2 * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])
    for noise, close in ((NOISE * S / v, True), (NOISE, False)):
        Rv = np.array([[(noise * R2_0) ** 2]])
        P_pred = scipy.linalg.solve_discrete_are(F.T, np.array([[1.0], [0.0]]), Q, Rv)
        assert np.allclose(F @ P_post @ F.T + Q, P_pred, rtol=1e-6) == close


def test_the_steady_gains_solve_the_riccati_equation():
    p, s, m = _records()
    for _ in range(400):  # the measurement agrees (r = 0): the covariance alone evolves
        kalman_update(p, s, m, 0.0, T)
    P_post = np.array([[s["kf_P00"], s["kf_P01"]], [s["kf_P01"], s["kf_P11"]]])
    F = np.array([[1.0, T], [0.0, 1.0]])
    q = (DRIFT * R2_0) ** 2
    Q = q * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])
    Rv = (NOISE * R2_0) ** 2
    # a-priori steady covariance: the filtering DARE (the dual of the control one)
    P_pred = scipy.linalg.solve_discrete_are(F.T, np.array([[1.0], [0.0]]), Q, np.array([[Rv]]))
    assert F @ P_post @ F.T + Q == pytest.approx(P_pred, rel=1e-6)
    K = P_pred[:, 0] / (P_pred[0, 0] + Rv)
    assert 0.2 < K[0] < 0.6  # the position gain these defaults give: per window, not a jump
    assert m["R2_hat"] == R2_0 and s["drift"] == 0.0


def test_a_ramp_of_R2_is_followed_with_no_steady_lag():
    p, s, m = _records()
    slope = 0.02 * R2_0  # ohm/s: +2 % of R2 per second (a fast heating)
    R2_true = R2_0
    lags = []
    for k in range(200):
        R2_true = R2_0 + slope * k * T
        kalman_update(p, s, m, _detected(m, R2_true), T)
        lags.append(m["R2_hat"] - R2_true)  # against the R2 the window measured
    assert abs(lags[-1]) < 1e-3 * R2_0
    assert s["drift"] == pytest.approx(slope, rel=0.02)
    assert max(abs(x) for x in lags[:20]) > 10 * abs(lags[-1])  # it did have to catch up


def test_a_step_is_closed_without_a_large_overshoot():
    p, s, m = _records(R2_hat=1.2 * R2_0)
    errs = []
    for _ in range(40):
        kalman_update(p, s, m, _detected(m, R2_0), T)
        errs.append(m["R2_hat"] / R2_0 - 1.0)
    assert abs(errs[-1]) < 1e-3
    assert min(errs) > -0.05  # from +20 %: under 5 % the other way
    assert abs(errs[3]) < 0.05  # within 5 % after four windows


def test_a_window_reading_R2_many_times_R2_hat_weighs_little():
    """The measured error's variance carried through ``z = R2_hat/(1 + r)``: with a wide prior
    (R2 known to 30 %, as after held windows) one window that reads ``r = -0.9`` (``z`` ten
    times R2_hat, the reading that took R2_hat to its clamp on Krause 50 hp near zero stator
    frequency, 2026-12-01) moves R2_hat by under 2 %, where the variance of ``r`` alone
    (``(kf_r^2 + (0.6 r)^2) R2_hat^2``) gives a gain of 0.24 and a step of 2.1 R2_hat."""
    p, s, m = _records()
    S = in_phase_sensitivity(2 * math.pi * F_INJ, (M + LL2) / R2_0)
    kalman_update(p, s, m, 0.9 * M * AMP * S, T)
    assert m["R2_hat"] / R2_0 - 1.0 < 0.02
    # a reading of the same size the other way (r = +0.9, z = R2_hat/1.9) still counts
    p, s, m = _records()
    kalman_update(p, s, m, -0.9 * M * AMP * S, T)
    assert m["R2_hat"] / R2_0 - 1.0 < -0.05


def test_a_gated_window_grows_the_covariance_and_moves_nothing():
    p, s, m = _records()
    for _ in range(50):
        kalman_update(p, s, m, 0.0, T)
    P00, R2 = s["kf_P00"], m["R2_hat"]
    kalman_hold(p, s, m, T)
    assert s["kf_P00"] > P00 and m["R2_hat"] == R2


def _run(machine, speed_pu, load_pu, ratio, estimator="mras", extra=()):
    mach = imdrive.machine_preset(machine)
    rp = rated_point(mach)
    n = speed_pu * rp.synchronous_speed_rpm
    T_L = load_pu * rp.torque_Nm
    sc = imdrive.Scenario.read(
        "injection-robust",
        [
            f"machine.preset='{machine}'",
            "compensator.step_law='kalman'",
            f"control.speed_feedback='{estimator}'",
            f"estimator.R2_ratio={ratio}",
            f"control.speed_ref_rpm={{initial=0, changes=[{{at=0.5, to={n:.3f}, over=1.0}}]}}",
            f"load.torque_Nm={{initial=0, changes=[{{at=2.0, to={T_L:.4f}}}]}}",
            *extra,
        ],
    )
    return imdrive.simulate(sc)


@pytest.mark.parametrize(
    "machine, speed_pu, load_pu, ratio",
    [
        ("paper-table-iv", 0.5, 0.5, 1.2),
        ("paper-table-iv", 1.0, 1.0, 0.8),
        ("aalto-2.2kw", 0.2, 1.0, 0.8),
        ("aalto-2.2kw", 0.1, -1.0, 1.2),
        ("krause-50hp", 0.1, -1.0, 1.2),
        ("krause-50hp", 0.05, 0.5, 1.2),
    ],
)
def test_the_drive_tracks_R2_with_the_kalman_law(machine, speed_pu, load_pu, ratio):
    res = _run(machine, speed_pu, load_pu, ratio)
    err = res["R2_hat_ohm"][-1] / res["R2_ohm"][-1] - 1.0
    assert abs(err) < 0.01, f"R2_hat ends {100 * err:+.2f} % off"
    assert res.verdict["verdict_ok"], res.verdict["verdict_text"]


@pytest.mark.parametrize(
    "machine, speed_pu, load_pu, ratio",
    [
        ("paper-table-iv", 0.1, -1.0, 1.2),
        ("paper-table-iv", 1.0, 1.0, 0.8),
        ("aalto-2.2kw", 0.2, 1.0, 0.8),
        ("aalto-2.2kw", 0.05, 0.5, 1.2),
    ],
)
def test_the_afo_tracks_R2_through_the_detectors_own_flux_error(machine, speed_pu, load_pu, ratio):
    """The AFO gives no flux error; the detection forms its own (kernels/flux_detector.py),
    and the same law converges (the scenario was refused before). R1_hat is exact: the AFO
    does not adapt R1, and the detector's voltage model carries an R1 error into R2_hat (from
    R1_hat = 1.1 R1 these four points ended +5.3, -19.7, -4.1 and within 1.5 %)."""
    res = _run(machine, speed_pu, load_pu, ratio, "afo", ["estimator.R1_ratio=1.0"])
    assert res.par.comp[0]["det"]
    err = res["R2_hat_ohm"][-1] / res["R2_ohm"][-1] - 1.0
    assert abs(err) < 0.015, f"R2_hat ends {100 * err:+.2f} % off"
    assert res.verdict["verdict_ok"], res.verdict["verdict_text"]


def test_the_mras_hands_its_own_flux_error_over():
    res = _run("paper-table-iv", 0.5, 0.5, 1.2)
    assert not res.par.comp[0]["det"]


@pytest.mark.slow
@pytest.mark.parametrize("ratio", [0.8, 1.2])
def test_the_law_closes_R2_where_the_detections_filter_weakens_it(ratio):
    """Krause 500 hp regenerating the rated torque at +1 Hz of stator frequency (the
    zero-frequency study's point): the detection's comparison filter leaves 0.15-0.17 of the
    analytic sensitivity at its 0.19 Hz injection. Dividing by the sensitivity R2_hat closed
    20 % in over 100 s and ended -7.0 % (from 0.8 R2) and -6.6 % (1.2); dividing by the
    filtered response both end within 0.25 %."""
    from imdrive.studies import zero_frequency

    scs, _ = zero_frequency.scenarios(
        ["krause-500hp"], (1.0,), (ratio,), drives=("injection-robust",)
    )
    res = imdrive.simulate(scs[0])
    err = res["R2_hat_ohm"][-1] / res["R2_ohm"][-1] - 1.0
    assert abs(err) < 0.01, f"R2_hat ends {100 * err:+.2f} % off"
    assert res.verdict["verdict_ok"], res.verdict["verdict_text"]
