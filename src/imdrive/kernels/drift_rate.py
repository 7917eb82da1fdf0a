"""The adaptive step law's drift rate: when it is integrated, and how fast it unwinds.

Inside the fine band the adaptive law (:func:`imdrive.kernels.compensator.compensator_update`)
adds a drift rate ``r`` (ohm per decision) to every update, integrated from the fine steps,
``r <- r + g dr``: a type-2 loop that follows a ramp of R2 (heating) with no steady lag. Two
rules shape ``g``, both on the detected error ``x`` (scaled) and its change ``dx`` since the
last decision:

* **Closing an error is not a ramp.** While the proportional step closes an error (``x``
  shrinks, ``x dx < 0``) integrating it would wind the drift up by ``drift_gain`` times the
  fine band's travel and overshoot by an equal area, so the drift is not integrated towards
  the error then. Only a shrink by more than ``p.drift_margin`` of ``|x|`` per decision
  counts: the proportional step closes 10-45 % of the error per decision, while a ramp's lag
  shrinks by the slow change of the detection's sensitivity as R2 moves. Without the margin
  that slow change held the drift at zero for a whole ramp from ``R2_hat(0) = 0.7 R2``
  (Table IV at 1.5 x rated speed, rated motoring torque, +20 % over 30 s: the in-phase
  sensitivity fell as T2 did, ``x`` shrank by 0.05 % per decision while the error grew, and
  R2_hat lagged 1.5 % as a type-1 loop).
* **A drift against a growing error is a ramp that stopped.** When ``x`` is against the drift
  and still grows (``x dx > 0``), the drift is unwound ``p.drift_unwind`` times faster, down
  to zero and not past it. When the plant's ramp stops the detection sees it a window late
  (the mean over a whole injection period), and the drift keeps walking R2_hat at the ramp's
  rate until the integral of the error unwinds it: on Table IV from 0.7 R2 at twice the rated
  speed, regenerating, the drift still carried 0.78 of the ramp's rate 1.7 s after the ramp
  stopped and R2_hat ended 0.93 % high (2.9 rpm at that speed; 0.22 % with this rule and
  :func:`~imdrive.kernels.sensitivity.fine_loop_gain_ratio`). Unwinding faster only while the
  error grows keeps the loop's damping where the error already closes: unwinding faster
  there too, the switching bridge at 1.5 x rated speed from R2_hat(0) = R2 swung +-1 %
  around the ramp (+-0.3 % with the plain rule).

With ``drift_unwind = 1`` and ``drift_margin = 0`` the rules are the plain ones: the drift is
unwound at its own gain and past zero, and any shrink is a closing.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def drift_update(p, s, x, dx, dr):
    """Integrate the fine step ``dr`` (ohm) into the drift rate ``s.drift`` (module docstring).

    Parameters
    ----------
    p : COMPENSATOR_PARAMS record
        ``drift_gain``, ``drift_max`` (ohm per decision), ``drift_unwind`` (at least 1),
        ``drift_margin`` (0: any shrink counts as closing).
    s : COMPENSATOR_STATE record
        ``drift``, updated.
    x : float
        The scaled detected error of this decision (inside the fine band).
    dx : float
        Its change since the last decision, same scaling.
    dr : float
        The fine step of this decision, ohm.
    """
    d0 = s.drift
    if x * d0 < 0.0:
        k = max(p.drift_unwind, 1.0) if x * dx > 0.0 else 1.0
        d = d0 + k * p.drift_gain * dr
        if p.drift_unwind > 1.0 and d * d0 < 0.0:
            d = 0.0  # unwound: a drift of the other sign is wound by the rules above
    elif x * dx >= -p.drift_margin * x * x:
        d = d0 + p.drift_gain * dr
    else:
        return
    s.drift = min(max(d, -p.drift_max), p.drift_max)
