"""Piecewise-linear time profiles, evaluated in the kernels (:mod:`imdrive.config.profiles`)."""

from numba import njit


@njit(cache=True)
def pwl_eval(t_pts, v_pts, n, t):
    """Value at time ``t`` of the piecewise-linear profile with ``n`` breakpoints.

    Right-continuous at steps (two breakpoints at one time); constant outside the breakpoints.
    """
    if t < t_pts[0]:
        return v_pts[0]
    i = 0
    while i + 1 < n and t_pts[i + 1] <= t:
        i += 1
    if i + 1 >= n:
        return v_pts[n - 1]
    dt = t_pts[i + 1] - t_pts[i]
    return v_pts[i] + (v_pts[i + 1] - v_pts[i]) * (t - t_pts[i]) / dt


@njit(cache=True)
def profile_at(prof_t, prof_v, prof_n, slot, t):
    """Value of profile ``slot`` at time ``t``."""
    return pwl_eval(prof_t[slot], prof_v[slot], prof_n[slot], t)
