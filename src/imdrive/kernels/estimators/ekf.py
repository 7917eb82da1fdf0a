"""Extended Kalman filter for speed and rotor resistance (continuous-discrete EKF).

State (6 reals, stationary frame): ``x = (i_alpha, i_beta, lam_alpha, lam_beta, w_r, R2)``,
stator current (A), rotor flux (Wb), electrical speed (rad/s), rotor resistance (ohm). Process
model: the machine of :mod:`imdrive.kernels.estimators.afo` (``k = M/L2``, ``sigma L1``,
``R_sigma = R1 + k^2 R2``) with the speed and the rotor resistance as random walks::

    p i   = (v - (R1 + k^2 R2) i + k (R2/L2) lam - j k w_r lam) / (sigma L1)
    p lam = (M R2/L2) i - (R2/L2) lam + j w_r lam
    p w_r = 0 + noise,      p R2 = 0 + noise

Measurement: the stator current sample, ``z = (i_alpha, i_beta) + noise``.

Each control period: the mean is predicted over the period that ended by one RK4 step (the
voltage applied over it held; exact enough that, with exact parameters, the filter has no
discretisation bias), the covariance by ``P <- F P F' + Q`` with ``F = I + Ts A(x)`` (``A`` the
Jacobian at the last estimate); then the standard update with the new current sample
(``K = P H' (H P H' + R)^-1``, ``H = [I2 0]``, ``P <- (I - K H) P``, symmetrised).

Noise (diagonal ``Q`` per period, scalar ``R``; defaults and their meaning in
:func:`imdrive.design.estimators.default_ekf_noise`): the current's process noise is the
voltage uncertainty ``(sigma_v Ts / sigma L1)^2``; the flux's is small (the model is trusted);
the speed's is an acceleration uncertainty ``(a Ts)^2``; R2's sets how fast it may drift.
``R2`` is estimated only with ``estimate_R2`` (else its row and column of ``P`` stay zero and it
follows the controller's ``R2_hat``); the engine writes it into the controller's model when
``estimator.R2_adaptation = "ekf"``. R2 and the speed are separable only under excitation
(slip or flux changes; see Kubota & Matsuse 1994 for the same limit on the observer).
"""

from __future__ import annotations

from imdrive.kernels.estimators.registry import register_kernel
from imdrive.kernels.jit import njit
from imdrive.kernels.model import model_inductances
from imdrive.kernels.records import b1, f8, record_dtype

N_X = 6

#: Parameters.
EKF_PARAMS = record_dtype(
    [
        ("q", f8, (N_X,)),  # process noise variances per period (A^2, Wb^2, (rad/s)^2, ohm^2)
        ("r", f8),  # measurement noise variance per current component, A^2
        ("p0", f8, (N_X,)),  # initial covariance (diagonal)
        ("estimate_R2", b1),  # R2 as a state (else held at the model's R2_hat)
        ("R2_min", f8),  # clamp of the R2 state, ohm
        ("R2_max", f8),
        ("write_R2", b1),  # write the R2 state into the controller's model (R2 adaptation)
    ]
)

#: State.
EKF_STATE = record_dtype(
    [
        ("x", f8, (N_X,)),  # estimate after the last update
        ("P", f8, (N_X, N_X)),  # its covariance
        ("F", f8, (N_X, N_X)),  # scratch
        ("W", f8, (N_X, N_X)),  # scratch
        ("started", b1),
        ("w_r_hat", f8),  # speed estimate, electrical rad/s (= x[4])
    ]
)


@njit(cache=True)
def _f(v_alpha, v_beta, ia, ib, la, lb, w, R2, R1, M, L2, sL1):
    k = M / L2
    Rs = R1 + k * k * R2
    a = R2 / L2
    dia = (v_alpha - Rs * ia + k * a * la + k * w * lb) / sL1
    dib = (v_beta - Rs * ib + k * a * lb - k * w * la) / sL1
    dla = M * a * ia - a * la - w * lb
    dlb = M * a * ib - a * lb + w * la
    return dia, dib, dla, dlb


@njit(cache=True, inline="always")
def _transition(F, ia, ib, la, lb, w, R2, R1, M, L2, sL1, Ts):
    """``F = I + Ts A`` with ``A`` the process model's Jacobian at ``(ia, ib, la, lb, w, R2)``
    (the alpha/beta current and rotor flux, the speed and R2 of the last estimate)."""
    k = M / L2
    a = R2 / L2
    Rs = R1 + k * k * R2
    F[:, :] = 0.0
    F[0, 0] = -Rs / sL1
    F[0, 2] = k * a / sL1
    F[0, 3] = k * w / sL1
    F[0, 4] = k * lb / sL1
    F[0, 5] = (-k * k * ia + k * la / L2) / sL1
    F[1, 1] = -Rs / sL1
    F[1, 2] = -k * w / sL1
    F[1, 3] = k * a / sL1
    F[1, 4] = -k * la / sL1
    F[1, 5] = (-k * k * ib + k * lb / L2) / sL1
    F[2, 0] = M * a
    F[2, 2] = -a
    F[2, 3] = -w
    F[2, 4] = -lb
    F[2, 5] = (M * ia - la) / L2
    F[3, 1] = M * a
    F[3, 2] = w
    F[3, 3] = -a
    F[3, 4] = la
    F[3, 5] = (M * ib - lb) / L2
    for r in range(N_X):
        for c in range(N_X):
            F[r, c] *= Ts
        F[r, r] += 1.0


@njit(cache=True, inline="always")
def _predict_mean(x, v_prev_alpha, v_prev_beta, R1, M, L2, sL1, Ts):
    """The mean's current and flux after one RK4 step over the period (the voltage held)."""
    ia, ib, la, lb, w, R2 = x[0], x[1], x[2], x[3], x[4], x[5]
    h = 0.5 * Ts
    k1 = _f(v_prev_alpha, v_prev_beta, ia, ib, la, lb, w, R2, R1, M, L2, sL1)
    k2 = _f(
        v_prev_alpha, v_prev_beta, ia + h * k1[0], ib + h * k1[1], la + h * k1[2], lb + h * k1[3],
        w, R2, R1, M, L2, sL1,
    )  # fmt: skip
    k3 = _f(
        v_prev_alpha, v_prev_beta, ia + h * k2[0], ib + h * k2[1], la + h * k2[2], lb + h * k2[3],
        w, R2, R1, M, L2, sL1,
    )  # fmt: skip
    k4 = _f(
        v_prev_alpha, v_prev_beta, ia + Ts * k3[0], ib + Ts * k3[1], la + Ts * k3[2],
        lb + Ts * k3[3], w, R2, R1, M, L2, sL1,
    )  # fmt: skip
    c6 = Ts / 6.0
    x[0] = ia + c6 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
    x[1] = ib + c6 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
    x[2] = la + c6 * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
    x[3] = lb + c6 * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3])


@njit(cache=True, inline="always")
def _predict_covariance(p, P, F, W):
    """``P <- F P F' + Q`` (``W`` scratch); R2's row and column stay zero unless estimated."""
    for r in range(N_X):
        for c in range(N_X):
            acc = 0.0
            for j in range(N_X):
                acc += F[r, j] * P[j, c]
            W[r, c] = acc
    for r in range(N_X):
        for c in range(r, N_X):
            acc = 0.0
            for j in range(N_X):
                acc += W[r, j] * F[c, j]
            P[r, c] = acc
            P[c, r] = acc
    for j in range(N_X):
        P[j, j] += p.q[j]
    if not p.estimate_R2:
        for j in range(N_X):
            P[5, j] = 0.0
            P[j, 5] = 0.0


@njit(cache=True, inline="always")
def _update(p, x, P, F, W, i_alpha, i_beta):
    """The measurement update with ``z = (i_alpha, i_beta)``, ``H = [I2 0]`` (``F``, ``W``
    scratch): ``K = P H' (H P H' + R)^-1``, ``x += K (z - H x)``, ``P <- P - K H P``,
    symmetrised."""
    s00 = P[0, 0] + p.r
    s01 = P[0, 1]
    s11 = P[1, 1] + p.r
    det = s00 * s11 - s01 * s01
    i00 = s11 / det
    i01 = -s01 / det
    i11 = s00 / det
    y0 = i_alpha - x[0]
    y1 = i_beta - x[1]
    for r in range(N_X):  # K = P[:, 0:2] S^-1, in W[:, 0:2]
        W[r, 0] = P[r, 0] * i00 + P[r, 1] * i01
        W[r, 1] = P[r, 0] * i01 + P[r, 1] * i11
    for r in range(N_X):
        x[r] += W[r, 0] * y0 + W[r, 1] * y1
    for r in range(N_X):  # P <- P - K H P = P - K P[0:2, :]
        for c in range(N_X):
            F[r, c] = W[r, 0] * P[0, c] + W[r, 1] * P[1, c]
    for r in range(N_X):
        for c in range(r, N_X):
            v = P[r, c] - 0.5 * (F[r, c] + F[c, r])
            P[r, c] = v
            P[c, r] = v


@njit(cache=True)
def ekf_step(p, m, s, v_prev_alpha, v_prev_beta, i_alpha, i_beta, Ts):
    """Predict over the period that ended, update with the current sample (updates ``s``).

    Parameters
    ----------
    p : EKF_PARAMS record
    m : MODEL_STATE record
        The controller's model: ``R1_hat``, inductances, and ``R2_hat`` (the initial R2 state).
    s : EKF_STATE record
        Updated in place; ``w_r_hat`` electrical rad/s, ``x[5]`` the R2 estimate, ohm.
    v_prev_alpha, v_prev_beta : float
        Voltage applied over the period that just ended, V.
    i_alpha, i_beta : float
        Stator current at this sample, A.
    Ts : float
        Control period, s.
    """
    x = s.x
    P = s.P
    if not s.started:
        x[:] = 0.0
        x[0] = i_alpha
        x[1] = i_beta
        x[5] = m.R2_hat
        P[:, :] = 0.0
        for j in range(N_X):
            P[j, j] = p.p0[j]
        if not p.estimate_R2:
            P[5, 5] = 0.0
        s.started = True
        s.w_r_hat = x[4]
        return
    M, L1, L2, sL1 = model_inductances(m)
    R1 = m.R1_hat
    if not p.estimate_R2:
        x[5] = m.R2_hat
    _transition(s.F, x[0], x[1], x[2], x[3], x[4], x[5], R1, M, L2, sL1, Ts)
    _predict_mean(x, v_prev_alpha, v_prev_beta, R1, M, L2, sL1, Ts)
    _predict_covariance(p, P, s.F, s.W)
    _update(p, x, P, s.F, s.W, i_alpha, i_beta)
    if p.estimate_R2:
        x[5] = min(max(x[5], p.R2_min), p.R2_max)
        if p.write_R2:
            m.R2_hat = x[5]
    s.w_r_hat = x[4]


@njit(cache=True)
def ekf_restart(m, s, i_ab):
    """Restart the state from the magnetised standstill (``EstimatorInput.restart``, as
    :func:`imdrive.kernels.estimators.afo.afo_restart`): the current ``i_ab``, the rotor flux
    ``M_hat i_ab``, the speed zero, R2 the controller's R2_hat (which the engine held through
    the test: kernels/stages.py); the covariance is kept."""
    s.x[0] = i_ab.real
    s.x[1] = i_ab.imag
    s.x[2] = m.M_hat * i_ab.real
    s.x[3] = m.M_hat * i_ab.imag
    s.x[4] = 0.0
    s.x[5] = m.R2_hat
    s.w_r_hat = 0.0


@njit(cache=True)
def ekf_estimate(p, m, s, inp):
    """The extended Kalman filter in the estimator contract; it has no flux error (``0j``)."""
    if inp.restart and s.started:
        ekf_restart(m, s, inp.i_prev_ab)
    ekf_step(p, m, s, inp.v_ab.real, inp.v_ab.imag, inp.i_ab.real, inp.i_ab.imag, inp.Ts)
    return s.w_r_hat, 0j


@njit(cache=True)
def ekf_flux(s):
    """The filter's rotor-flux estimate, stationary frame, Wb."""
    return complex(s.x[2], s.x[3])


KERNEL = register_kernel("ekf", EKF_PARAMS, EKF_STATE, ekf_estimate, flux=ekf_flux)
