"""The closed loop's one-period map in the controller's synchronous frame: fixed point, Jacobian.

The whole drive (plant, sensors, MRAS, IFOC, inverter) is invariant under a rotation of every
stationary-frame quantity by one angle: rotating the plant fluxes, the MRAS fluxes, the held
voltage and the stored current sample by ``e^{j a}`` and the controller's field angle by ``a``
rotates the next period's state by the same ``e^{j a}`` (the speed, the integrators in the
controller's frame and the flux model are unchanged). With the compensator frozen (its R2_hat a
constant) and constant references, the drive's steady state is therefore a periodic orbit
whose every sample is the same point *in the controller's frame*. :func:`rotated_map` is that
reduced map: set the field angle to zero (so the stationary frame is the controller's frame at
this sample), run one control period of :func:`imdrive.kernels.engine.run_drive` (unchanged),
and rotate the result by ``e^{-j theta_e'}``, the angle the controller advanced. Its fixed points
are the drive's steady states; its Jacobian at one is the exact small-signal model of the
*discrete* closed loop at the control period Ts (the neutral rotation mode is gone with the
angle, and the mechanical angle, winding temperatures and energy accumulators, which never feed
back, are not states: temperatures are held at the state's values).

The reduced state ``z`` (SI units, synchronous frame of the controller): the plant's and the
controller's :data:`N_D` states, then the estimator's own (its ``ReducedState``,
:mod:`imdrive.kernels.estimators.registry`: the MRAS's, the adaptive observer's, the
reactive-power MRAS's; an estimator without one is refused by the maps):

====== ============================== =================================================
index  field                          block
====== ============================== =================================================
0, 1   ``psi_s_ab`` (d, q)            plant stator flux, Wb
2, 3   ``psi_r_ab``                   plant rotor flux, Wb
4      ``w_m``                        plant speed, mechanical rad/s
5, 6   ``v_prev_ab``                  voltage held over the last period, V
7, 8   ``i_prev_ab``                  last current sample, A
9      ``int_w``                      speed PI integral, A
10, 11 ``int_dq``                     current PI integrals, V
12     ``psi_hat``                    the controller's rotor-flux model, Wb
13...  the estimator's                MRAS (22 in all): ``lam_v``, ``lam_i``,
                                      ``lam_f`` (d, q), ``int_e``, ``w_r_hat``, the
                                      type-2 integral (0 where held); adaptive
                                      observer (21 in all): ``i_hat``, ``lam``, ``e``
                                      (d, q), ``int_e``, ``w_r_hat``; reactive-power
                                      MRAS (17): ``lam`` (d, q), ``int_e``, ``w_r_hat``
====== ============================== =================================================

The two inputs are the speed reference (mechanical rad/s) and the load torque (N m), slots 0
of the profiles ``PR_SPEED_REF`` and ``PR_LOAD`` (the caller makes both profiles constant).
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.kernels.engine import LOG, S_OK
from imdrive.kernels.engine_call import call_engine, engine_address
from imdrive.kernels.estimators import mras
from imdrive.kernels.estimators.common import to_frame
from imdrive.kernels.estimators.reduced import (
    estimator_reduce,
    estimator_restore,
    reduced_state_of,
)
from imdrive.kernels.jit import njit
from imdrive.kernels.profiles import PR_LOAD, PR_SPEED_REF
from imdrive.kernels.recording import RECORDING
from imdrive.kernels.threads import over_threads, slots

N_D = 13  # the plant's and the controller's states; the estimator's follow
N_Z = 22  # the MRAS drive's reduced state (any drive's: len(state_scale(S)))
N_U = 2

# status of a point (also used by imdrive.stability)
P_OK = 0
P_NO_CONVERGENCE = 1  # Newton did not reach the fixed point
P_DIVERGED = 2  # the one-period map left the engine's bounds (NaN, current, speed)

#: typical magnitude of the plant's and the controller's states, for finite-difference steps
#: and the residual norm (the estimator's: its ``ReducedState.scale``)
DRIVE_SCALE = np.array(
    [
        0.1, 0.1, 0.1, 0.1, 1.0,  # plant
        1.0, 1.0, 0.1, 0.1,  # sample
        0.1, 1.0, 1.0, 0.1,  # control
    ]
)  # fmt: skip
#: the MRAS drive's scales (kept for callers of the 22-state map; any drive's: state_scale)
Z_SCALE = np.concatenate([DRIVE_SCALE, mras.REDUCED_SCALE])


def state_scale(S) -> np.ndarray:
    """Typical magnitude of every state of the reduced state of ``S``'s drive (its length is
    the reduced state's; the estimator's from its ``ReducedState.scale``)."""
    return np.concatenate([DRIVE_SCALE, reduced_state_of(S).scale])


@njit(cache=True)
def pack_state(P, S, i, z):
    """Write the reduced state of drive ``i`` (rotated into the controller's frame) into ``z``
    (the estimator's states by its ``ReducedState.reduce``)."""
    x = S.plant[i]
    smp = S.sample[i]
    ctl = S.control[i]
    th = ctl.theta_e
    c = (math.cos(th), math.sin(th))
    z[0], z[1] = to_frame(c, x.psi_s_ab)
    z[2], z[3] = to_frame(c, x.psi_r_ab)
    z[4] = x.w_m
    z[5], z[6] = to_frame(c, smp.v_prev_ab)
    z[7], z[8] = to_frame(c, smp.i_prev_ab)
    z[9] = ctl.int_w
    z[10] = ctl.int_dq.real
    z[11] = ctl.int_dq.imag
    z[12] = ctl.psi_hat
    estimator_reduce(P.est[i], S.est[i], c, z, N_D)


@njit(cache=True)
def unpack_state(z, S, i):
    """Write ``z`` into drive ``i`` with the field angle 0 (stationary = controller's frame)."""
    x = S.plant[i]
    smp = S.sample[i]
    ctl = S.control[i]
    x.psi_s_ab = complex(z[0], z[1])
    x.psi_r_ab = complex(z[2], z[3])
    x.w_m = z[4]
    smp.v_prev_ab = complex(z[5], z[6])
    smp.i_prev_ab = complex(z[7], z[8])
    ctl.theta_e = 0.0
    ctl.int_w = z[9]
    ctl.int_dq = complex(z[10], z[11])
    ctl.psi_hat = z[12]
    estimator_restore(z, N_D, S.est[i])


@njit(cache=True)
def _engine(P, S, i, n_steps, k0, engine):
    """``run_drive`` for ``n_steps`` periods of drive ``i`` from period ``k0``, nothing logged,
    through its address ``engine`` (:func:`map_engine`) with the argument types of
    ``simulate()``'s call (int64, bool, ``rec`` a zero-length recording): the engine ``run``
    compiled, not linked into the map's kernels (:mod:`imdrive.kernels.engine_call`)."""
    return call_engine(
        engine, P, S, i, np.int64(n_steps), np.empty(0, dtype=LOG), np.int64(0), np.int64(k0),
        np.bool_(False), np.zeros(0, dtype=RECORDING),
    )  # fmt: skip


def map_engine(P, S) -> int:
    """The engine's address for the map's kernels on parameters ``P`` and state ``S``
    (:func:`imdrive.kernels.engine_call.engine_address`)."""
    return engine_address(P, S, np.empty(0, dtype=LOG))


@njit(cache=True)
def rotated_map(P, S, i, z, zout, th1, th2, engine):
    """One control period of drive ``i`` from reduced state ``z``; reduced result in ``zout``.

    ``th1``, ``th2`` are the (frozen) winding temperatures, degC. Returns the engine status.
    """
    unpack_state(z, S, i)
    x = S.plant[i]
    x.theta1 = th1
    x.theta2 = th2
    status, _ = _engine(P, S, i, 1, 0, engine)
    pack_state(P, S, i, zout)
    return status


@njit(cache=True)
def _jacobian(P, S, i, z, zs, th1, th2, A, Bu, fp, fm, zp, engine):
    """Central finite differences of :func:`rotated_map` in ``z`` (``A``) and the inputs (``Bu``);
    ``zs``: the states' scales (:func:`state_scale`).

    Returns the worst engine status met.
    """
    bad = S_OK
    n = z.shape[0]
    for j in range(n):
        h = 1e-6 * (abs(z[j]) + zs[j])
        zp[:] = z
        zp[j] = z[j] + h
        s1 = rotated_map(P, S, i, zp, fp, th1, th2, engine)
        zp[j] = z[j] - h
        s2 = rotated_map(P, S, i, zp, fm, th1, th2, engine)
        if s1 != S_OK or s2 != S_OK:
            bad = max(s1, s2)
        for r in range(n):
            A[r, j] = (fp[r] - fm[r]) / (2.0 * h)
    pv = P.prof_v[i]
    for k in range(N_U):
        slot = PR_SPEED_REF if k == 0 else PR_LOAD
        u0 = pv[slot, 0]
        h = 1e-6 * (abs(u0) + 1.0)
        pv[slot, 0] = u0 + h
        s1 = rotated_map(P, S, i, z, fp, th1, th2, engine)
        pv[slot, 0] = u0 - h
        s2 = rotated_map(P, S, i, z, fm, th1, th2, engine)
        pv[slot, 0] = u0
        if s1 != S_OK or s2 != S_OK:
            bad = max(s1, s2)
        for r in range(n):
            Bu[r, k] = (fp[r] - fm[r]) / (2.0 * h)
    return bad


@njit(cache=True)
def _residual_norm(f, z, zs):
    worst = 0.0
    for j in range(z.shape[0]):
        d = abs(f[j] - z[j]) / (abs(z[j]) + zs[j])
        if not math.isfinite(d):
            return math.inf
        worst = max(worst, d)
    return worst


@njit(cache=True)
def _newton_step(A, r, dz, M):
    """``dz`` solving ``(A - I) dz = r`` by Gaussian elimination with partial pivoting;
    ``M`` is scratch of ``A``'s shape. Returns False where the matrix is singular.

    ``np.linalg.solve`` (LAPACK's ``gesv``, the same elimination) brings its shape checks and
    error messages into the map's first compile: 2.5-3 s of it (numba's unicode and
    ``repr`` functions among them, 2026-11-30), for a 22 x 22 system.
    """
    n = r.shape[0]
    for a in range(n):
        for b in range(n):
            M[a, b] = A[a, b] - (1.0 if a == b else 0.0)
        dz[a] = r[a]
    for c in range(n):
        p = c
        for a in range(c + 1, n):
            if abs(M[a, c]) > abs(M[p, c]):
                p = a
        if M[p, c] == 0.0:
            return False
        if p != c:
            for b in range(c, n):
                M[c, b], M[p, b] = M[p, b], M[c, b]
            dz[c], dz[p] = dz[p], dz[c]
        for a in range(c + 1, n):
            m = M[a, c] / M[c, c]
            for b in range(c + 1, n):
                M[a, b] -= m * M[c, b]
            dz[a] -= m * dz[c]
    for c in range(n - 1, -1, -1):
        acc = dz[c]
        for b in range(c + 1, n):
            acc -= M[c, b] * dz[b]
        dz[c] = acc / M[c, c]
    return True


@njit(cache=True)
def solve_point(P, S, i, z, zs, th1, th2, A, Bu, tol, max_iter, engine):
    """Newton's method on ``rotated_map(z) - z`` from ``z`` (in place), then the Jacobians.

    Each iteration solves ``(A - I) dz = z - F(z)`` with the central-difference Jacobian ``A``
    and halves the step while the scaled residual does not fall (at most 8 times).

    Parameters
    ----------
    P, S : DriveParams, DriveState
        ``S`` row ``i`` is scratch.
    z : float64[n]
        Initial guess; the fixed point on return (``n``: the drive's reduced state).
    zs : float64[n]
        The states' scales (:func:`state_scale`).
    th1, th2 : float
        Frozen winding temperatures, degC.
    A : float64[n, n], Bu : float64[n, N_U]
        Outputs: ``dF/dz`` and ``dF/du`` at the fixed point.
    tol : float
        Largest scaled residual ``|F_j - z_j| / (|z_j| + zs_j)`` accepted.
    max_iter : int
    engine : int
        The engine's address (:func:`map_engine`).

    Returns
    -------
    status : int
        ``P_OK``, ``P_NO_CONVERGENCE`` or ``P_DIVERGED``.
    residual : float
        Scaled residual at the returned ``z``.
    iterations : int
    """
    n = z.shape[0]
    f = np.empty(n)
    fp = np.empty(n)
    fm = np.empty(n)
    zp = np.empty(n)
    zt = np.empty(n)
    dz = np.empty(n)
    M = np.empty((n, n))
    st = rotated_map(P, S, i, z, f, th1, th2, engine)
    if st != S_OK:
        return P_DIVERGED, math.inf, 0
    res = _residual_norm(f, z, zs)
    it = 0
    while res > tol and it < max_iter:
        it += 1
        _jacobian(P, S, i, z, zs, th1, th2, A, Bu, fp, fm, zp, engine)
        for r in range(n):
            for c in range(n):
                if not math.isfinite(A[r, c]):
                    return P_DIVERGED, res, it
        if not _newton_step(A, z - f, dz, M):
            return P_NO_CONVERGENCE, res, it
        lam = 1.0
        accepted = False
        for _ in range(9):
            for j in range(n):
                zt[j] = z[j] + lam * dz[j]
            st = rotated_map(P, S, i, zt, fp, th1, th2, engine)
            r_new = _residual_norm(fp, zt, zs) if st == S_OK else math.inf
            if r_new < res:
                accepted = True
                break
            lam *= 0.5
        if not accepted:
            return P_NO_CONVERGENCE, res, it
        z[:] = zt
        f[:] = fp
        res = r_new
    if res > tol:
        return P_NO_CONVERGENCE, res, it
    st = _jacobian(P, S, i, z, zs, th1, th2, A, Bu, fp, fm, zp, engine)
    if st != S_OK:
        return P_DIVERGED, res, it
    return P_OK, res, it


@njit(cache=True, entry=True, nogil=True)
def _solve_some(
    P, S, Z, zs, TH, A, Bu, status, residual, iterations, tol, max_iter, engine, first, n
):
    """:func:`solve_point` for drives ``first, first + n, ...`` (one thread's share)."""
    for i in range(first, Z.shape[0], n):
        st, res, it = solve_point(
            P, S, i, Z[i], zs, TH[i, 0], TH[i, 1], A[i], Bu[i], tol, max_iter, engine
        )
        status[i] = st
        residual[i] = res
        iterations[i] = it


def solve_points(P, S, Z, TH, A, Bu, status, residual, iterations, tol, max_iter, engine=None):
    """:func:`solve_point` for every drive ``i`` of ``P``/``S`` (rows of ``Z``, ``A``, ...),
    over the cores (:func:`imdrive.kernels.threads.over_threads`); ``engine``: the engine's
    address (:func:`map_engine`; default: looked up here)."""
    engine = map_engine(P, S) if engine is None else engine
    zs = state_scale(S)
    n = slots(Z.shape[0])

    def share(first):
        _solve_some(
            P, S, Z, zs, TH, A, Bu, status, residual, iterations, float(tol), int(max_iter),
            engine, first, n,
        )  # fmt: skip

    over_threads(share, n)


def propagate(P, S, i, z, n_steps, th1, th2, zout, engine=None):
    """Run ``n_steps`` periods of drive ``i`` from reduced state ``z`` in one engine call.

    The field angle turns freely over the run; the reduced state at the end (rotated by the
    final angle) goes into ``zout``. Used to check the linearisation against the nonlinear loop.
    ``engine``: the engine's address (:func:`map_engine`; default: looked up here).
    """
    engine = map_engine(P, S) if engine is None else engine
    return _propagate(P, S, int(i), z, int(n_steps), float(th1), float(th2), zout, engine)


@njit(cache=True, entry=True)
def _propagate(P, S, i, z, n_steps, th1, th2, zout, engine):
    unpack_state(z, S, i)
    x = S.plant[i]
    x.theta1 = th1
    x.theta2 = th2
    status, _ = _engine(P, S, i, n_steps, 0, engine)
    pack_state(P, S, i, zout)
    return status


def step_check(P, S, Z0, Z1, TH, n_steps, n_win, peaks, status, engine=None):
    """Simulate every drive ``i`` from ``Z0[i]``; per window, its largest distance to ``Z1[i]``.

    ``Z0`` is the starting reduced state (a fixed point, perturbed), ``Z1`` the fixed point of
    the drive's own (stepped) references, the state a stable loop settles to. The distance is
    ``max_j |z_j - Z1_j| / (|Z1_j| + s_j)`` (``s``: :func:`state_scale`) of the reduced state
    (rotated into the controller's frame every period); ``peaks[i, w]`` is its largest value
    over periods ``w n_win ... (w + 1) n_win - 1``. ``status[i]`` is the engine status (a
    diverged drive keeps NaN in the windows it did not reach). ``engine``: the engine's address
    (:func:`map_engine`; default: looked up here).
    """
    engine = map_engine(P, S) if engine is None else engine
    zs = state_scale(S)
    n = slots(Z0.shape[0])

    def share(first):
        _check_some(P, S, Z0, Z1, zs, TH, int(n_steps), int(n_win), peaks, status, engine, first, n)

    over_threads(share, n)


@njit(cache=True, entry=True, nogil=True)
def _check_some(P, S, Z0, Z1, zs, TH, n_steps, n_win, peaks, status, engine, first, n):
    """:func:`step_check` for drives ``first, first + n, ...`` (one thread's share)."""
    for i in range(first, Z0.shape[0], n):
        unpack_state(Z0[i], S, i)
        x = S.plant[i]
        x.theta1 = TH[i, 0]
        x.theta2 = TH[i, 1]
        z = np.empty(Z0.shape[1])
        for w in range(peaks.shape[1]):
            peaks[i, w] = np.nan
        st = S_OK
        for k in range(n_steps):
            st, _ = _engine(P, S, i, 1, k, engine)
            if st != S_OK:
                break
            pack_state(P, S, i, z)
            e = 0.0
            for j in range(z.shape[0]):
                e = max(e, abs(z[j] - Z1[i, j]) / (abs(Z1[i, j]) + zs[j]))
            w = k // n_win
            if w < peaks.shape[1]:
                if not (peaks[i, w] >= e):
                    peaks[i, w] = e
        status[i] = st
