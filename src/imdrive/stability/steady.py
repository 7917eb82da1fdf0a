"""The continuous steady state of the field-oriented loop with imposed currents: the initial
guess of the discrete fixed point (:mod:`imdrive.stability.linear`, section *Method*)."""

from __future__ import annotations

import numpy as np

from imdrive.kernels.estimators import mras
from imdrive.run import linear as rl

# ------------------------------------------------------------------------------------------
# continuous steady state (initial guess)


def _plant_in_frame(c, iq, w_m, w_ref):
    """Currents, fluxes, synchronous speed and torque for imposed ``id* + j iq*``."""
    i_d = min(c["psi_ref"] / c["M_hat"], 1e300)
    I = i_d + 1j * iq
    w_fb = w_ref if c["sensorless"] else w_m
    w_sl_cmd = c["R2_hat"] * iq / (c["L2_hat"] * i_d)
    w_e = c["n_p"] * w_fb + w_sl_cmd
    slip = w_e - c["n_p"] * w_m
    psi_r = c["M"] * I / (1.0 + 1j * slip * c["L2"] / c["R2"])
    i_r = (psi_r - c["M"] * I) / c["L2"]
    psi_s = c["L1"] * I + c["M"] * i_r
    T_e = 1.5 * c["n_p"] * (psi_s.real * iq - psi_s.imag * i_d)
    return I, psi_s, psi_r, w_e, T_e


def _residuals(c, iq, w_m, w_ref, T_L):
    I, psi_s, _, w_e, T_e = _plant_in_frame(c, iq, w_m, w_ref)
    T_load = T_L + (c["B"] + c["k_visc"]) * w_m + c["k_fan"] * w_m * np.abs(w_m)
    r1 = (T_e - T_load) / (1.5 * c["n_p"] * c["psi_ref"])  # in A of iq
    if c["sensorless"]:
        w_safe = np.where(np.abs(w_e) < 1e-9, 1e-9, w_e)
        r2 = c["sL1_hat"] * iq - psi_s.imag + (c["R1"] - c["R1_hat"]) * I.real / w_safe
        r2 = r2 / c["psi_ref"] * (c["psi_ref"] / c["M_hat"])  # in A
    else:
        r2 = (w_m - w_ref) * c["J"]
    return r1, r2


def continuous_steady_state(c: dict, w_ref, T_L, n_iter: int = 40):
    """Solve the continuous steady state for ``(iq*, w_m)`` at every ``(w_ref, T_L)`` pair.

    Newton's method, vectorised over the points, with a finite-difference 2 x 2 Jacobian
    (equations in the module docstring).

    Returns
    -------
    iq, w_m : ndarray
        q current (A) and true mechanical speed (rad/s).
    ok : ndarray of bool
        Converged to a residual below 1e-9 A.
    """
    w_ref = np.asarray(w_ref, dtype=float)
    T_L = np.asarray(T_L, dtype=float)
    k_t = 1.5 * c["n_p"] * c["M"] / c["L2"] * c["psi_ref"]
    T_req = T_L + (c["B"] + c["k_visc"]) * w_ref + c["k_fan"] * w_ref * np.abs(w_ref)
    iq = T_req / k_t
    w_m = w_ref + (c["R2_hat"] / c["R2"] - 1.0) * (c["R2"] / c["L2"]) * iq / (
        c["psi_ref"] / c["M_hat"]
    ) / c["n_p"] * float(c["sensorless"])
    ok = np.zeros(w_ref.shape, dtype=bool)
    with np.errstate(all="ignore"):
        for _ in range(n_iter):
            r1, r2 = _residuals(c, iq, w_m, w_ref, T_L)
            ok = np.isfinite(r1) & np.isfinite(r2) & (np.abs(r1) < 1e-9) & (np.abs(r2) < 1e-9)
            if ok.all():
                break
            h1 = 1e-7 * (np.abs(iq) + 1.0)
            h2 = 1e-7 * (np.abs(w_m) + 1.0)
            a1, a2 = _residuals(c, iq + h1, w_m, w_ref, T_L)
            b1, b2 = _residuals(c, iq, w_m + h2, w_ref, T_L)
            j11, j21 = (a1 - r1) / h1, (a2 - r2) / h1
            j12, j22 = (b1 - r1) / h2, (b2 - r2) / h2
            det = j11 * j22 - j12 * j21
            d_iq = (-r1 * j22 + r2 * j12) / det
            d_wm = (-j11 * r2 + j21 * r1) / det
            # limit the step: at most 20 A and 50 rad/s per iteration
            d_iq = np.clip(d_iq, -20.0, 20.0)
            d_wm = np.clip(d_wm, -50.0, 50.0)
            iq = np.where(ok, iq, iq + d_iq)
            w_m = np.where(ok, w_m, w_m + d_wm)
    return iq, w_m, ok & np.isfinite(iq) & np.isfinite(w_m)


def _initial_state(c: dict, Ts: float, iq, w_m, w_ref, P, S) -> np.ndarray:
    """Reduced states (N, n) of the continuous steady state, as seen at a sample instant: the
    plant's and the controller's, then the estimator's from its ``ReducedState.steady``
    (``P``, ``S``: the drive's records)."""
    I, psi_s, psi_r, w_e, _ = _plant_in_frame(c, iq, w_m, w_ref)
    n = len(iq)
    i_d = I.real
    v = c["R1"] * I + 1j * w_e * psi_s
    # the voltage held over the last period and the last sample, in this sample's frame
    v_prev = v * np.exp(-0.5j * w_e * Ts)
    i_prev = I * np.exp(-1j * w_e * Ts)
    psi_hat = c["M_hat"] * i_d
    ff = np.zeros(n, dtype=complex)
    if c["decouple"]:
        ff = -w_e * c["sL1_hat"] * iq + 1j * w_e * (
            c["sL1_hat"] * i_d + c["M_hat"] / c["L2_hat"] * psi_hat
        )
    int_dq = v - ff
    z = np.zeros((n, rl.N_D))
    for k, val in ((0, psi_s), (2, psi_r), (5, v_prev), (7, i_prev), (10, int_dq)):
        z[:, k] = val.real
        z[:, k + 1] = val.imag
    z[:, 4] = w_m
    z[:, 9] = iq
    z[:, 12] = psi_hat
    w_r_hat = c["n_p"] * (w_ref if c["sensorless"] else w_m)
    steady = rl.reduced_state_of(S).steady
    est = steady(dict(c, v=v), P.est[0], I, w_e, np.broadcast_to(w_r_hat, (n,)))
    return np.concatenate([z, est], axis=1)


def second_integrator_runs(c: dict, w_e) -> np.ndarray:
    """Where the type-2 MRAS's second integrator runs at the stator frequency ``w_e`` (rad/s):
    ``b2 > 0`` and ``|w_e| >= b2_wmin`` of ``c`` (an MRAS drive's constants,
    :func:`imdrive.run.linear.model_coefficients`; kernels/estimators/mras.py)."""
    return mras.second_integrator_runs({k: c.get(k, 0.0) for k in ("b2", "b2_wmin")}, w_e)
