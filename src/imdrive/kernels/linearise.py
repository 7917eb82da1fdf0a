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

The reduced state ``z`` (:data:`N_Z` reals, synchronous frame of the controller; SI units):

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
13, 14 ``lam_v_ab``                   MRAS reference model (filtered), Wb
15, 16 ``lam_i_ab``                   MRAS adjustable model, Wb
17, 18 ``lam_f_ab``                   MRAS adjustable model, filtered, Wb
19     ``int_e``                      MRAS integral of the error, Wb^2 s
20     ``w_r_hat``                    MRAS speed estimate, electrical rad/s
21     ``int_w``                      type-2 MRAS's second integrator, rad (0 while it
                                      is held, below its stator frequency, or type 1)
====== ============================== =================================================

The type-2 MRAS (``mras.acceleration_tracking``) adds its second integrator to the state
where it runs; where it is held (below ``b2_wmin`` of stator frequency) its value is a
constant offset of the speed estimate that does not change the small-signal model, and the
state is held at 0 (its row of the Jacobian is zero: an eigenvalue 0, not the neutral 1 of a
value that never moves).

The two inputs are the speed reference (mechanical rad/s) and the load torque (N m), slots 0
of the profiles ``PR_SPEED_REF`` and ``PR_LOAD`` (the caller makes both profiles constant).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from imdrive.kernels.engine import LOG, S_OK
from imdrive.kernels.engine_call import call_engine, engine_address
from imdrive.kernels.profiles import PR_LOAD, PR_SPEED_REF
from imdrive.kernels.recording import RECORDING
from imdrive.kernels.threads import over_threads, slots

N_Z = 22
N_U = 2

# status of a point (also used by imdrive.stability)
P_OK = 0
P_NO_CONVERGENCE = 1  # Newton did not reach the fixed point
P_DIVERGED = 2  # the one-period map left the engine's bounds (NaN, current, speed)

#: typical magnitude of each state, for finite-difference steps and the residual norm
Z_SCALE = np.array(
    [
        0.1, 0.1, 0.1, 0.1, 1.0,  # plant
        1.0, 1.0, 0.1, 0.1,  # sample
        0.1, 1.0, 1.0, 0.1,  # control
        0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 1e-4, 1.0, 1.0,  # mras
    ]
)  # fmt: skip


@njit(cache=True)
def _rot(c, a, b):
    """``e^{-j theta} (a + j b)`` with ``c = (cos theta, sin theta)``, as two floats."""
    return c[0] * a + c[1] * b, -c[1] * a + c[0] * b


@njit(cache=True)
def pack_state(S, i, z, b2=0.0):
    """Write the reduced state of drive ``i`` (rotated into the controller's frame) into ``z``;
    ``b2``: its MRAS's second-integrator corner (``P.est[i].b2``; 0: type 1)."""
    x = S.plant[i]
    smp = S.sample[i]
    ctl = S.control[i]
    est = S.est[i]  # an MRAS drive: the only estimator the reduced state carries
    th = ctl.theta_e
    c = (math.cos(th), math.sin(th))
    z[0], z[1] = _rot(c, x.psi_s_ab.real, x.psi_s_ab.imag)
    z[2], z[3] = _rot(c, x.psi_r_ab.real, x.psi_r_ab.imag)
    z[4] = x.w_m
    z[5], z[6] = _rot(c, smp.v_prev_ab.real, smp.v_prev_ab.imag)
    z[7], z[8] = _rot(c, smp.i_prev_ab.real, smp.i_prev_ab.imag)
    z[9] = ctl.int_w
    z[10] = ctl.int_dq.real
    z[11] = ctl.int_dq.imag
    z[12] = ctl.psi_hat
    z[13], z[14] = _rot(c, est.lam_v_ab.real, est.lam_v_ab.imag)
    z[15], z[16] = _rot(c, est.lam_i_ab.real, est.lam_i_ab.imag)
    z[17], z[18] = _rot(c, est.lam_f_ab.real, est.lam_f_ab.imag)
    z[19] = est.int_e
    z[20] = est.w_r_hat
    # the second integrator where it runs (type 2, above its stator frequency), else held at 0
    z[21] = est.int_w if est.int_w_run and b2 > 0.0 else 0.0


@njit(cache=True)
def unpack_state(z, S, i):
    """Write ``z`` into drive ``i`` with the field angle 0 (stationary = controller's frame)."""
    x = S.plant[i]
    smp = S.sample[i]
    ctl = S.control[i]
    est = S.est[i]  # an MRAS drive: the only estimator the reduced state carries
    x.psi_s_ab = complex(z[0], z[1])
    x.psi_r_ab = complex(z[2], z[3])
    x.w_m = z[4]
    smp.v_prev_ab = complex(z[5], z[6])
    smp.i_prev_ab = complex(z[7], z[8])
    ctl.theta_e = 0.0
    ctl.int_w = z[9]
    ctl.int_dq = complex(z[10], z[11])
    ctl.psi_hat = z[12]
    est.lam_v_ab = complex(z[13], z[14])
    est.lam_i_ab = complex(z[15], z[16])
    est.lam_f_ab = complex(z[17], z[18])
    est.int_e = z[19]
    est.w_r_hat = z[20]
    est.int_w = z[21]


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
    pack_state(S, i, zout, P.est[i].b2)
    return status


@njit(cache=True)
def _jacobian(P, S, i, z, th1, th2, A, Bu, fp, fm, zp, engine):
    """Central finite differences of :func:`rotated_map` in ``z`` (``A``) and the inputs (``Bu``).

    Returns the worst engine status met.
    """
    bad = S_OK
    for j in range(N_Z):
        h = 1e-6 * (abs(z[j]) + Z_SCALE[j])
        zp[:] = z
        zp[j] = z[j] + h
        s1 = rotated_map(P, S, i, zp, fp, th1, th2, engine)
        zp[j] = z[j] - h
        s2 = rotated_map(P, S, i, zp, fm, th1, th2, engine)
        if s1 != S_OK or s2 != S_OK:
            bad = max(s1, s2)
        for r in range(N_Z):
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
        for r in range(N_Z):
            Bu[r, k] = (fp[r] - fm[r]) / (2.0 * h)
    return bad


@njit(cache=True)
def _residual_norm(f, z):
    worst = 0.0
    for j in range(N_Z):
        d = abs(f[j] - z[j]) / (abs(z[j]) + Z_SCALE[j])
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
def solve_point(P, S, i, z, th1, th2, A, Bu, tol, max_iter, engine):
    """Newton's method on ``rotated_map(z) - z`` from ``z`` (in place), then the Jacobians.

    Each iteration solves ``(A - I) dz = z - F(z)`` with the central-difference Jacobian ``A``
    and halves the step while the scaled residual does not fall (at most 8 times).

    Parameters
    ----------
    P, S : DriveParams, DriveState
        ``S`` row ``i`` is scratch.
    z : float64[N_Z]
        Initial guess; the fixed point on return.
    th1, th2 : float
        Frozen winding temperatures, degC.
    A : float64[N_Z, N_Z], Bu : float64[N_Z, N_U]
        Outputs: ``dF/dz`` and ``dF/du`` at the fixed point.
    tol : float
        Largest scaled residual ``|F_j - z_j| / (|z_j| + Z_SCALE_j)`` accepted.
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
    f = np.empty(N_Z)
    fp = np.empty(N_Z)
    fm = np.empty(N_Z)
    zp = np.empty(N_Z)
    zt = np.empty(N_Z)
    dz = np.empty(N_Z)
    M = np.empty((N_Z, N_Z))
    st = rotated_map(P, S, i, z, f, th1, th2, engine)
    if st != S_OK:
        return P_DIVERGED, math.inf, 0
    res = _residual_norm(f, z)
    it = 0
    while res > tol and it < max_iter:
        it += 1
        _jacobian(P, S, i, z, th1, th2, A, Bu, fp, fm, zp, engine)
        for r in range(N_Z):
            for c in range(N_Z):
                if not math.isfinite(A[r, c]):
                    return P_DIVERGED, res, it
        if not _newton_step(A, z - f, dz, M):
            return P_NO_CONVERGENCE, res, it
        lam = 1.0
        accepted = False
        for _ in range(9):
            for j in range(N_Z):
                zt[j] = z[j] + lam * dz[j]
            st = rotated_map(P, S, i, zt, fp, th1, th2, engine)
            r_new = _residual_norm(fp, zt) if st == S_OK else math.inf
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
    st = _jacobian(P, S, i, z, th1, th2, A, Bu, fp, fm, zp, engine)
    if st != S_OK:
        return P_DIVERGED, res, it
    return P_OK, res, it


@njit(cache=True, nogil=True)
def _solve_some(P, S, Z, TH, A, Bu, status, residual, iterations, tol, max_iter, engine, first, n):
    """:func:`solve_point` for drives ``first, first + n, ...`` (one thread's share)."""
    for i in range(first, Z.shape[0], n):
        st, res, it = solve_point(
            P, S, i, Z[i], TH[i, 0], TH[i, 1], A[i], Bu[i], tol, max_iter, engine
        )
        status[i] = st
        residual[i] = res
        iterations[i] = it


def solve_points(P, S, Z, TH, A, Bu, status, residual, iterations, tol, max_iter, engine=None):
    """:func:`solve_point` for every drive ``i`` of ``P``/``S`` (rows of ``Z``, ``A``, ...),
    over the cores (:func:`imdrive.kernels.threads.over_threads`); ``engine``: the engine's
    address (:func:`map_engine`; default: looked up here)."""
    engine = map_engine(P, S) if engine is None else engine
    n = slots(Z.shape[0])

    def share(first):
        _solve_some(
            P, S, Z, TH, A, Bu, status, residual, iterations, float(tol), int(max_iter), engine,
            first, n,
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


@njit(cache=True)
def _propagate(P, S, i, z, n_steps, th1, th2, zout, engine):
    unpack_state(z, S, i)
    x = S.plant[i]
    x.theta1 = th1
    x.theta2 = th2
    status, _ = _engine(P, S, i, n_steps, 0, engine)
    pack_state(S, i, zout, P.est[i].b2)
    return status


def step_check(P, S, Z0, Z1, TH, n_steps, n_win, peaks, status, engine=None):
    """Simulate every drive ``i`` from ``Z0[i]``; per window, its largest distance to ``Z1[i]``.

    ``Z0`` is the starting reduced state (a fixed point, perturbed), ``Z1`` the fixed point of
    the drive's own (stepped) references, the state a stable loop settles to. The distance is
    ``max_j |z_j - Z1_j| / (|Z1_j| + Z_SCALE_j)`` of the reduced state (rotated into the
    controller's frame every period); ``peaks[i, w]`` is its largest value over periods
    ``w n_win ... (w + 1) n_win - 1``. ``status[i]`` is the engine status (a diverged drive
    keeps NaN in the windows it did not reach). ``engine``: the engine's address
    (:func:`map_engine`; default: looked up here).
    """
    engine = map_engine(P, S) if engine is None else engine
    n = slots(Z0.shape[0])

    def share(first):
        _check_some(P, S, Z0, Z1, TH, int(n_steps), int(n_win), peaks, status, engine, first, n)

    over_threads(share, n)


@njit(cache=True, nogil=True)
def _check_some(P, S, Z0, Z1, TH, n_steps, n_win, peaks, status, engine, first, n):
    """:func:`step_check` for drives ``first, first + n, ...`` (one thread's share)."""
    for i in range(first, Z0.shape[0], n):
        unpack_state(Z0[i], S, i)
        x = S.plant[i]
        x.theta1 = TH[i, 0]
        x.theta2 = TH[i, 1]
        z = np.empty(N_Z)
        for w in range(peaks.shape[1]):
            peaks[i, w] = np.nan
        st = S_OK
        for k in range(n_steps):
            st, _ = _engine(P, S, i, 1, k, engine)
            if st != S_OK:
                break
            pack_state(S, i, z, P.est[i].b2)
            e = 0.0
            for j in range(N_Z):
                e = max(e, abs(z[j] - Z1[i, j]) / (abs(Z1[i, j]) + Z_SCALE[j]))
            w = k // n_win
            if w < peaks.shape[1]:
                if not (peaks[i, w] >= e):
                    peaks[i, w] = e
        status[i] = st
