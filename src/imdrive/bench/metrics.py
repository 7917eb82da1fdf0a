"""The bench's metrics, computed from one run's logged signals (decimated log, SI columns of
:class:`~imdrive.run.result.SimulationResult`): the figures and the table come from the same
numbers.

Per run, with ``e = speed - speed_ref`` and the windows of :class:`~imdrive.bench.protocol.Case`:

* ``steady_speed_error_rpm``: mean of ``e`` over the last :data:`STEADY_WINDOW_S`;
* ``rms_speed_error_rpm``: RMS of ``e`` from ``t_eval`` to the end (the event under test);
* ``speed_est_error_rpm``: mean of ``speed_est - speed`` over the last :data:`STEADY_WINDOW_S`
  (``speed_est`` is the estimate the controller uses);
* ``rms_speed_est_error_rpm``: its RMS from ``t_eval`` to the end;
* ``R2_error_pct``: ``100 (R̂2 - R2)/R2`` at the end;
* ``R2_time_to_2pct_s``: first time after which ``|R̂2 - R2| <= 2 % R2`` holds to the end (0 if
  it always does, NaN if not at the end);
* ``peak_current_A``: largest ``|i_s|`` logged;
* ``lost_control``: the run diverged, or ``|e|`` exceeded :func:`lost_bound_rpm`
  (``LOST_ABS_RPM + LOST_REL |speed_ref|``) without interruption for longer than
  :data:`LOST_TIME_S` after ``t_eval``. (Computed here from the log, independent of any flag
  of the engine.)
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.run.columns import with_current_names

STEADY_WINDOW_S = 0.5
R2_BAND = 0.02
LOST_ABS_RPM = 50.0
LOST_REL = 0.2
LOST_TIME_S = 0.3

METRICS = (
    "steady_speed_error_rpm",
    "rms_speed_error_rpm",
    "speed_est_error_rpm",
    "rms_speed_est_error_rpm",
    "R2_error_pct",
    "R2_time_to_2pct_s",
    "peak_current_A",
    "lost_control",
)


def lost_bound_rpm(speed_ref_rpm):
    """Speed-error bound beyond which control is counted as lost.

    Parameters
    ----------
    speed_ref_rpm : float or ndarray
        Speed reference, rpm.

    Returns
    -------
    float or ndarray
        The bound on the speed error, rpm: a fixed part plus a fraction of the reference.
    """
    return LOST_ABS_RPM + LOST_REL * np.abs(speed_ref_rpm)


def _longest_run(mask: np.ndarray, dt: float) -> float:
    """Longest uninterrupted stretch of True in ``mask``, s."""
    best = cur = 0
    for m in mask:
        cur = cur + 1 if m else 0
        best = max(best, cur)
    return best * dt


def run_metrics(sig, t_eval_s: float, diverged: bool) -> dict:
    """The metrics of one run from its signals (mapping of column -> array).

    Parameters
    ----------
    sig : Mapping[str, array_like]
        The run's columns, each in the unit its name ends with: it needs ``time_s``,
        ``speed_rpm``, ``speed_ref_rpm``, ``speed_est_rpm``, ``R2_hat_ohm``, ``R2_ohm``,
        ``i_alpha_A``, ``i_beta_A``.
    t_eval_s : float
        Start of the window of the RMS and lost-control metrics, s.
    diverged : bool
        The run diverged: every metric but ``lost_control`` is NaN.

    Returns
    -------
    dict
        Metric name (:data:`METRICS`, unit in the name) -> value.
    """
    sig = with_current_names(sig)  # a mapping with an old column name still works
    t = np.asarray(sig["time_s"])
    w = np.asarray(sig["speed_rpm"])
    ref = np.asarray(sig["speed_ref_rpm"])
    est = np.asarray(sig["speed_est_rpm"])
    R2h = np.asarray(sig["R2_hat_ohm"])
    R2 = np.asarray(sig["R2_ohm"])
    i_mag = np.hypot(sig["i_alpha_A"], sig["i_beta_A"])
    dt = float(t[1] - t[0]) if len(t) > 1 else 0.0
    nan = math.nan
    e = w - ref
    steady = t >= t[-1] - STEADY_WINDOW_S + 1e-12
    ev = t >= t_eval_s
    lost = bool(diverged) or _longest_run(np.abs(e[ev]) > lost_bound_rpm(ref[ev]), dt) > LOST_TIME_S
    rel = np.abs(R2h - R2) / R2
    bad = np.nonzero(~(rel <= R2_BAND))[0]
    if len(bad) == 0:
        t2 = 0.0
    elif bad[-1] == len(t) - 1:
        t2 = nan
    else:
        t2 = float(t[bad[-1] + 1])
    ok = not diverged
    return {
        "steady_speed_error_rpm": float(np.mean(e[steady])) if ok else nan,
        "rms_speed_error_rpm": float(np.sqrt(np.mean(e[ev] ** 2))) if ok else nan,
        "speed_est_error_rpm": float(np.mean((est - w)[steady])) if ok else nan,
        "rms_speed_est_error_rpm": float(np.sqrt(np.mean((est - w)[ev] ** 2))) if ok else nan,
        "R2_error_pct": float(100.0 * (R2h[-1] - R2[-1]) / R2[-1]),
        "R2_time_to_2pct_s": t2 if ok else nan,
        "peak_current_A": float(np.max(i_mag)),
        "lost_control": lost,
    }
