"""Piecewise-linear time profiles, evaluated in the kernels (:mod:`imdrive.config.profiles`)."""

from imdrive.kernels.jit import njit

# profile slots (rows of the drive's profile arrays): piecewise-linear functions of time
PR_SPEED_REF = 0  # speed reference, mechanical rad/s
PR_LOAD = 1  # time-dependent part of the load torque, N m
PR_R1_SCALE = 2  # plant R1 multiplier (1 = reference value)
PR_R2_SCALE = 3  # plant R2 multiplier
PR_V_AMP = 4  # open-loop voltage: space-vector amplitude (= phase peak), V
PR_FREQ = 5  # open-loop voltage: frequency, Hz
PR_SPEED_IMPOSED = 6  # imposed mechanical speed, rad/s (plant speed_imposed)
PR_FLUX_REF = 7  # rotor-flux reference, Wb
N_PROF = 8


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


@njit(cache=True, inline="always")
def profile_at(prof_t, prof_v, prof_n, slot, t):
    """Value of profile ``slot`` at time ``t``. Inlined: the loop calls it with each slot a
    constant, and numba compiled a function of its own for each (8 of them, 0.7 s of a cold
    start)."""
    return pwl_eval(prof_t[slot], prof_v[slot], prof_n[slot], t)
