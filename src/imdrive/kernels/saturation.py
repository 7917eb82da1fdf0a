"""Main-flux saturation of the plant: the magnetising curve, its inverse and the currents.

The magnetising flux ``psi_m = psi_s - Ll1 i_s = psi_r - Ll2 i_r`` and current
``i_m = i_s + i_r`` follow the curve (see :mod:`imdrive.kernels.machine`)::

    i_m = (psi_m / Lm0) (1 + (|psi_m| / psi_sat)^S)

Given the fluxes, ``psi_m`` is parallel to ``psi_x = psi_s/Ll1 + psi_r/Ll2`` and its magnitude
solves a scalar monotone equation, solved from a table of the inverse curve built once per run
plus one Newton correction (:func:`magnetising_ratio`, :func:`saturation_table`; Newton's
method to convergence outside the table). :mod:`imdrive.kernels.machine` uses these functions
(and re-exports them) for the plant's currents and magnetic energy.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from imdrive.kernels.jit import njit

#: Cells of the inverse magnetising-curve table (:func:`saturation_table`).
SAT_CELLS = 12
#: Largest relative error of the table's ``k`` (after its Newton correction) that
#: :func:`saturation_table` accepts; past it the table is left out and the full solve used.
SAT_TABLE_TOL = 1e-9


@njit(cache=True)
def _power(y, S):
    """``y**S`` for ``y >= 0``; by repeated squaring when ``S`` is a small whole number (the
    saturation curve is evaluated several times per RK4 stage: ``pow`` would dominate)."""
    n = int(S)
    if n == S and 0 < n <= 64:
        r = 1.0
        b = y
        while n > 0:
            if n & 1:
                r *= b
            b *= b
            n >>= 1
        return r
    return y**S


@njit(cache=True)
def magnetising_current(psi_m, Lm0, psi_sat, S):
    """Magnitude of the magnetising current on the curve at flux magnitude ``psi_m``, A."""
    return psi_m / Lm0 * (1.0 + _power(psi_m / psi_sat, S))


@njit(cache=True)
def magnetising_energy(psi_m, Lm0, psi_sat, S):
    """Energy of the magnetising branch per unit 1.5, ``int_0^psi_m i_m dpsi``, J."""
    return psi_m * psi_m / (2.0 * Lm0) + psi_m ** (S + 2.0) / ((S + 2.0) * Lm0 * psi_sat**S)


@njit(cache=True)
def _solve_magnetising(p, X, m):
    """Newton's method on ``G m + i_m(m) = X`` from ``m`` to convergence; returns ``m`` and
    ``F'(m)`` (the full solve: used where the table does not reach)."""
    G = 1.0 / p.Ll1 + 1.0 / p.Ll2
    dF = G + 1.0 / p.Lm0
    for _ in range(30):
        r = _power(m / p.psi_sat, p.S)
        F = G * m + m / p.Lm0 * (1.0 + r) - X
        dF = G + (1.0 + (p.S + 1.0) * r) / p.Lm0
        step = F / dF
        m -= step
        # Newton converges quadratically: after a step of relative size 1e-8 the error left
        # is of order 1e-16, so one more iteration would only confirm it
        if abs(step) <= 1e-8 * m:
            break
    return m, dF


@njit(cache=True)
def magnetising_ratio(p, X):
    """``k = |psi_m| / |psi_x|`` at ``|psi_x| = X`` (H) and its derivative ``dk/dX`` (H/A).

    ``|psi_m| = m`` solves ``F(m) = G m + i_m(m) = X`` (:func:`saturated_currents`). Inside
    the table (``X < p.sat_X_max``, built once per run by :func:`saturation_table`): a cubic
    Hermite interpolation of ``k`` on a uniform grid in ``X``, then one Newton correction of
    ``m`` (no loop: from the table's relative error ``e`` it leaves ``~ S e^2``, below
    ``SAT_TABLE_TOL``, which :func:`saturation_table` checks when it builds the table).
    Outside the table (deep saturation, or no table): Newton's method to convergence.
    """
    G = 1.0 / p.Ll1 + 1.0 / p.Ll2
    if X <= 0.0:
        return 1.0 / (G + 1.0 / p.Lm0), 0.0
    if X < p.sat_X_max:
        s = X * p.sat_inv_h
        j = min(int(s), SAT_CELLS - 1)
        t = s - j
        t2 = t * t
        t3 = t2 * t
        k = (
            (2.0 * t3 - 3.0 * t2 + 1.0) * p.sat_k[j]
            + (t3 - 2.0 * t2 + t) * p.sat_dk[j]
            + (3.0 * t2 - 2.0 * t3) * p.sat_k[j + 1]
            + (t3 - t2) * p.sat_dk[j + 1]
        )
        m = k * X
        r = _power(m * p.sat_inv_psi_sat, p.S)
        F = p.sat_G * m + m * p.sat_inv_Lm0 * (1.0 + r) - X
        inv_dF = 1.0 / (p.sat_G + (1.0 + (p.S + 1.0) * r) * p.sat_inv_Lm0)
        m -= F * inv_dF
    else:
        m, dF = _solve_magnetising(p, X, X / (G + 1.0 / p.M))
        inv_dF = 1.0 / dF
    inv_X = 1.0 / X
    k = m * inv_X
    return k, (inv_dF - k) * inv_X


@njit(cache=True)
def magnetising_ratio_series(p, X):
    """``k`` (:func:`magnetising_ratio`) and its first two derivatives in ``u = X^2``.

    Returns ``(k, dk/du, d2k/du2)`` (H, H/A^2, H/A^4) from the curve's derivatives at the
    solution: with ``F(m) = G m + i_m(m)``, ``m' = 1/F'``, ``m'' = -F'' m'^3``, then
    ``k' = (m' - k)/X``, ``k'' = (m'' - 2 k')/X`` in ``X``, and ``dk/du = k'/(2X)``,
    ``d2k/du2 = (k'' - k'/X)/(4 X^2)``. The switching bridge expands ``k`` to second order
    in ``u`` about the period's start (no square root, no solve inside the period).
    """
    k, k1 = magnetising_ratio(p, X)
    if X <= 1e-9 * p.sat_X_max or X <= 0.0:
        return k, 0.0, 0.0
    m = k * X
    inv_X = 1.0 / X  # the divisions below are multiplies by it (one serial division left)
    r = _power(m * p.sat_inv_psi_sat, p.S)
    dF = p.sat_G + (1.0 + (p.S + 1.0) * r) * p.sat_inv_Lm0
    d2F = (p.S + 1.0) * p.S * r * p.sat_inv_Lm0 / m
    m1 = 1.0 / dF
    m2 = -d2F * m1 * m1 * m1
    k2 = (m2 - 2.0 * k1) * inv_X
    inv_2X = 0.5 * inv_X
    return k, k1 * inv_2X, (k2 - k1 * inv_X) * inv_2X * inv_2X


def saturation_table(Ll1: float, Ll2: float, Lm0: float, psi_sat: float, S: float) -> dict:
    """The inverse magnetising curve tabulated once per run (the ``sat_*`` plant fields).

    Built once per curve and process (the drives of a batch or a sweep mostly share one
    machine: building and checking a table costs ~15 ms, as much as a second of the realistic
    drive); every call returns a fresh dict with its own arrays.

    ``k(X) = m/X`` with ``m`` the solution of ``(1/Ll1 + 1/Ll2) m + i_m(m) = X``, at
    ``SAT_CELLS + 1`` nodes uniform in ``X`` from 0 to ``F(1.6 psi_sat)`` (1.6 times the
    saturation flux: past 2 times the rated flux with the default curve), with the exact
    derivatives ``dk/dX = (1/F'(m) - k)/X`` for a cubic Hermite interpolation. The table is
    checked here on 20 001 points against Newton's method run to convergence, with the one
    Newton correction :func:`magnetising_ratio` applies; if the relative error of ``k``
    exceeds ``SAT_TABLE_TOL`` (a curve too sharp for the grid) the table is left out
    (``sat_X_max = 0``) and the kernel solves the curve by Newton everywhere.

    Returns
    -------
    dict
        ``sat_X_max`` (A), ``sat_inv_h`` (1/A), ``sat_k`` (H), ``sat_dk`` (H, times the cell
        width) and ``sat_table_error`` (the measured relative error of ``k``, not a field).
    """
    table = _saturation_table(float(Ll1), float(Ll2), float(Lm0), float(psi_sat), float(S))
    return {name: v.copy() if isinstance(v, np.ndarray) else v for name, v in table.items()}


@functools.lru_cache(maxsize=64)
def _saturation_table(Ll1: float, Ll2: float, Lm0: float, psi_sat: float, S: float) -> dict:
    """:func:`saturation_table`, built (the caller copies it)."""
    G = 1.0 / Ll1 + 1.0 / Ll2

    def F(m):
        return G * m + m / Lm0 * (1.0 + (m / psi_sat) ** S)

    def dF(m):
        return G + (1.0 + (S + 1.0) * (m / psi_sat) ** S) / Lm0

    def solve(X):
        m = X / (G + 1.0 / Lm0)
        for _ in range(200):
            step = (F(m) - X) / dF(m)
            m = m - step
            if np.all(np.abs(step) <= 1e-15 * np.maximum(m, 1e-300)):
                break
        return m

    X_max = float(F(1.6 * psi_sat))
    old_err = np.seterr(over="ignore", invalid="ignore")  # a sharp curve overflows: refused
    h = X_max / SAT_CELLS
    X = np.linspace(0.0, X_max, SAT_CELLS + 1)
    m = solve(X)
    k = np.empty_like(X)
    dk = np.empty_like(X)
    k[0] = 1.0 / (G + 1.0 / Lm0)
    dk[0] = 0.0
    k[1:] = m[1:] / X[1:]
    dk[1:] = (1.0 / dF(m[1:]) - k[1:]) / X[1:]
    # check: the kernel's formula (Hermite, then one Newton step) against the full solve
    Xc = np.linspace(0.0, X_max, 20001)[1:-1]
    s = Xc / h
    j = np.minimum(s.astype(int), SAT_CELLS - 1)
    t = s - j
    kc = (
        (2 * t**3 - 3 * t**2 + 1) * k[j]
        + (t**3 - 2 * t**2 + t) * h * dk[j]
        + (3 * t**2 - 2 * t**3) * k[j + 1]
        + (t**3 - t**2) * h * dk[j + 1]
    )
    mc = kc * Xc
    mc = mc - (F(mc) - Xc) / dF(mc)
    err = float(np.max(np.abs(mc / solve(Xc) - 1.0)))
    np.seterr(**old_err)
    ok = bool(np.isfinite(err) and err <= SAT_TABLE_TOL)
    return {
        "sat_X_max": X_max if ok else 0.0,
        "sat_inv_h": 1.0 / h if ok else 0.0,
        "sat_G": G,
        "sat_inv_Lm0": 1.0 / Lm0,
        "sat_inv_psi_sat": 1.0 / psi_sat,
        "sat_k": k if ok else np.zeros_like(k),
        "sat_dk": h * dk if ok else np.zeros_like(dk),
        "sat_table_error": err,
    }


@njit(cache=True)
def saturated_currents(p, psi_s_alpha, psi_s_beta, psi_r_alpha, psi_r_beta, m0=-1.0):
    """Stator and rotor currents with main-flux saturation, A; and ``|psi_m|``, Wb.

    ``psi_m = k psi_x`` with ``psi_x = psi_s/Ll1 + psi_r/Ll2``, where ``m = |psi_m|`` solves
    ``G m + i_m(m) = |psi_x|``, ``G = 1/Ll1 + 1/Ll2`` (monotone and convex), and
    ``k = m/|psi_x|`` comes from :func:`magnetising_ratio` (the run's table, or Newton's
    method where it does not reach). ``m0`` is not used (kept for the call signature).
    """
    x_alpha = psi_s_alpha / p.Ll1 + psi_r_alpha / p.Ll2
    x_beta = psi_s_beta / p.Ll1 + psi_r_beta / p.Ll2
    X = math.sqrt(x_alpha * x_alpha + x_beta * x_beta)
    k, _ = magnetising_ratio(p, X)
    pm_alpha = k * x_alpha
    pm_beta = k * x_beta
    i_s_alpha = (psi_s_alpha - pm_alpha) / p.Ll1
    i_s_beta = (psi_s_beta - pm_beta) / p.Ll1
    i_r_alpha = (psi_r_alpha - pm_alpha) / p.Ll2
    i_r_beta = (psi_r_beta - pm_beta) / p.Ll2
    return i_s_alpha, i_s_beta, i_r_alpha, i_r_beta, k * X
