"""The full-order observer (AFO) and the extended Kalman filter alone, on hand-made records.

The measurements come from the machine's equations in the stationary frame, discretised
exactly here (matrix exponential, voltage held over each period) at a fixed speed::

    sigma L1 p i = v - (R1 + k^2 R2) i + k (1/T2 - j w_r) lam,   k = M/L2, T2 = L2/R2
    p lam        = (M/T2) i - (1/T2 - j w_r) lam

With exact parameters the true state is a fixed point of each estimator (to the accuracy of
its one RK4 step per period), and from a wrong speed each converges to the true one.
"""

import math

import numpy as np
import pytest
from scipy.linalg import expm

from imdrive.config.machine import machine_preset
from imdrive.design.estimators import default_afo_gains, default_ekf_noise
from imdrive.kernels.estimators.afo import AFO_PARAMS, AFO_STATE, adaptation_share, afo_step
from imdrive.kernels.estimators.ekf import EKF_PARAMS, EKF_STATE, ekf_step
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.records import new_record

TS = 1e-4
MACHINE = machine_preset()
R1, R2 = MACHINE.R1_ohm, MACHINE.R2_ohm
LL1, LL2, M = MACHINE.Ll1_H, MACHINE.Ll2_H, MACHINE.M_H
L1, L2 = LL1 + M, LL2 + M
SIGMA_L1 = L1 - M * M / L2
W_R = 2 * math.pi * 30.0  # electrical rotor speed, rad/s
W_E = 2 * math.pi * 31.5  # stator frequency: a motoring slip
V_AMP = 130.0  # V, peak phase voltage


def _model():
    return new_record(MODEL_STATE, R1_hat=R1, R2_hat=R2, Ll1_hat=LL1, Ll2_hat=LL2, M_hat=M)[0]


def _plant_matrices():
    """``x' = A x + B v`` for x = (i_alpha, i_beta, lam_alpha, lam_beta), exact over Ts."""
    k = M / L2
    a = R2 / L2
    Rs = R1 + k * k * R2
    A = np.array(
        [
            [-Rs / SIGMA_L1, 0.0, k * a / SIGMA_L1, k * W_R / SIGMA_L1],
            [0.0, -Rs / SIGMA_L1, -k * W_R / SIGMA_L1, k * a / SIGMA_L1],
            [M * a, 0.0, -a, -W_R],
            [0.0, M * a, W_R, -a],
        ]
    )
    B = np.zeros((4, 2))
    B[0, 0] = B[1, 1] = 1.0 / SIGMA_L1
    big = np.zeros((6, 6))
    big[:4, :4] = A * TS
    big[:4, 4:] = B * TS
    E = expm(big)
    return E[:4, :4], E[:4, 4:]


@pytest.fixture(scope="module")
def trajectory():
    """``(v[k], x[k])``: the voltage held over period k and the state at sample k, from the
    periodic steady state on (2 s of settling, then 1 s)."""
    Phi, Gam = _plant_matrices()
    n_settle, n = 20000, 10000
    x = np.zeros(4)
    vs, xs = [], []
    for k in range(n_settle + n):
        ph = W_E * (k + 0.5) * TS
        v = V_AMP * np.array([math.cos(ph), math.sin(ph)])
        if k >= n_settle:
            vs.append(v)
            xs.append(x.copy())
        x = Phi @ x + Gam @ v
    return np.array(vs), np.array(xs)


def test_the_trajectory_is_the_machines_steady_state(trajectory):
    """The generator's check: the flux magnitude is steady and rotates at the stator
    frequency, and current and flux satisfy the flux equation's phasor steady state (to the
    held voltage's ripple at the samples, 5e-4 here; a wrong sign of the speed term would
    miss by a factor of ten)."""
    _, x = trajectory
    lam = x[:, 2] + 1j * x[:, 3]
    i = x[:, 0] + 1j * x[:, 1]
    assert np.ptp(np.abs(lam)) < 1e-6 * np.abs(lam).mean()
    w = np.angle(lam[1:] / lam[:-1]) / TS
    assert np.allclose(w, W_E, rtol=1e-9)
    # steady state of the flux equation: (M/T2) i = (1/T2 + j (w_e - w_r)) lam
    T2 = L2 / R2
    assert np.allclose((M / T2) * i, (1 / T2 + 1j * (W_E - W_R)) * lam, rtol=2e-3)


def _afo(Kp_scale=1.0):
    Kp, Ki, _, _ = default_afo_gains(
        0.9, R1, R2, SIGMA_L1, M, L2, 0.0, 2 * math.pi * 20.0, 0.0, 0.0
    )
    p = new_record(AFO_PARAMS, Kp=Kp * Kp_scale, Ki=Ki * Kp_scale, R_min=0.5, R_max=1.5)[0]
    return p, Ki * Kp_scale


def _run_afo(trajectory, w0, n):
    v, x = trajectory
    p, Ki = _afo()
    m = _model()
    s = np.zeros(1, dtype=AFO_STATE)[0]
    s["i_hat_ab"] = complex(x[0, 0], x[0, 1])
    s["lam_ab"] = complex(x[0, 2], x[0, 3])
    s["int_e"] = w0 / Ki
    s["w_r_hat"] = w0
    w, e = [], []
    for k in range(1, n):
        afo_step(p, m, s, v[k - 1, 0], v[k - 1, 1], x[k, 0], x[k, 1], TS)
        w.append(s["w_r_hat"])
        e.append(abs(s["e_ab"]))
    return np.array(w), np.array(e), s


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_afo_true_state_is_a_fixed_point(trajectory):
    w, e, s = _run_afo(trajectory, W_R, 5000)
    assert np.max(np.abs(w - W_R)) < 1e-4 * W_R
    assert np.max(e) < 1e-6  # A
    lam = complex(*trajectory[1][4999, 2:])
    assert abs(s["lam_ab"] - lam) < 1e-7


def test_afo_converges_from_a_wrong_speed(trajectory):
    w, e, _ = _run_afo(trajectory, 0.9 * W_R, 10000)
    err0 = 0.1 * W_R
    assert abs(w[-1] - W_R) < 1e-3 * err0  # a thousandth of the initial error after 1 s
    assert abs(w[1000] - W_R) < 0.3 * err0  # and most of it within 0.1 s
    assert np.max(e) > 1e-3  # the error was seen in the current


def _ekf(estimate_R2):
    q, r, p0 = default_ekf_noise(TS, SIGMA_L1, 0.9, R2, 5.0, 0.1, 2000.0, 0.5, 0.05)
    p = new_record(
        EKF_PARAMS, q=q, r=r, p0=p0, estimate_R2=estimate_R2, R2_min=0.5 * R2, R2_max=2 * R2
    )[0]
    return p


def _run_ekf(trajectory, w0, n, estimate_R2=False):
    v, x = trajectory
    p = _ekf(estimate_R2)
    m = _model()
    s = np.zeros(1, dtype=EKF_STATE)[0]
    s["x"][:] = [*x[0], w0, R2]
    s["P"][:, :] = np.diag(p["p0"])
    if not estimate_R2:
        s["P"][5, 5] = 0.0
    s["started"] = True
    w, r2 = [], []
    for k in range(1, n):
        ekf_step(p, m, s, v[k - 1, 0], v[k - 1, 1], x[k, 0], x[k, 1], TS)
        w.append(s["w_r_hat"])
        r2.append(s["x"][5])
    return np.array(w), np.array(r2), s


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@pytest.mark.parametrize("estimate_R2", [False, True])
def test_ekf_true_state_is_a_fixed_point(trajectory, estimate_R2):
    w, r2, s = _run_ekf(trajectory, W_R, 5000, estimate_R2)
    assert np.max(np.abs(w - W_R)) < 1e-4 * W_R
    assert np.max(np.abs(r2 - R2)) < 1e-4 * R2
    assert np.allclose(s["x"][:4], trajectory[1][4999], atol=1e-6)
    P = s["P"]
    assert np.allclose(P, P.T) and np.all(np.linalg.eigvalsh(P) > -1e-15)


def test_ekf_first_call_starts_from_the_measured_current():
    p, m = _ekf(False), _model()
    s = np.zeros(1, dtype=EKF_STATE)[0]
    ekf_step(p, m, s, 0.0, 0.0, 3.0, -1.0, TS)
    assert s["started"] and list(s["x"]) == [3.0, -1.0, 0.0, 0.0, 0.0, R2]
    assert np.array_equal(np.diag(s["P"]), [*p["p0"][:5], 0.0])


def test_ekf_converges_from_a_wrong_speed(trajectory):
    w, _, _ = _run_ekf(trajectory, 0.9 * W_R, 10000)
    err0 = 0.1 * W_R
    assert abs(w[-1] - W_R) < 1e-3 * err0
    assert abs(w[2000] - W_R) < 0.3 * err0


def test_the_speed_adaptation_slows_below_a_sixth_of_its_bandwidth():
    """``adaptation_share``: full where the sixth harmonic of the stator frequency reaches
    the bandwidth, that share below it, never under half; no schedule without ``a_w``."""
    a_w = 2 * math.pi * 80.0
    p = new_record(AFO_PARAMS, a_w=a_w)[0]
    assert adaptation_share(p, a_w / 6.0) == 1.0
    assert adaptation_share(p, 10 * a_w) == 1.0
    assert adaptation_share(p, -0.75 * a_w / 6.0) == pytest.approx(0.75, rel=1e-12)
    assert adaptation_share(p, 0.0) == 0.5
    assert adaptation_share(new_record(AFO_PARAMS)[0], 0.0) == 1.0


def test_a_share_scales_both_adaptation_gains(trajectory):
    """The share is the bandwidth's: ``Kp`` and ``Ki`` both scale (their ratio, the
    cancelled pole, stays), so from the same start the estimate moves half as far in a step
    at half the share."""
    v, x = trajectory
    p, Ki = _afo()
    w0 = 0.9 * W_R
    moved = []
    for share in (1.0, 0.5):
        s = np.zeros(1, dtype=AFO_STATE)[0]
        s["i_hat_ab"] = complex(x[0, 0], x[0, 1])
        s["lam_ab"] = complex(x[0, 2], x[0, 3])
        s["int_e"] = w0 / Ki
        s["w_r_hat"] = w0
        afo_step(p, _model(), s, v[0, 0], v[0, 1], x[1, 0], x[1, 1], TS, share)
        moved.append(s["w_r_hat"] - w0)
    assert moved[0] != 0.0
    assert moved[1] == pytest.approx(0.5 * moved[0], rel=1e-9)
