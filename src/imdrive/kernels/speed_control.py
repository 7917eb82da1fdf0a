"""The speed PI's gains in field weakening (``CONTROL_PARAMS.w_fw_sched``).

A sensorless estimator that models the rotor with ``R2_hat`` reads the slip through it: in
steady state the MRAS's estimate is ``w_r_hat = w_r - (R2_hat/R2 - 1) w_s``, and with the
slip ``w_s = (M R2/L2) i_q / psi`` the estimate's error is proportional to the torque current.
Through the speed PI that is a positive feedback of ``i_q`` on itself,
``g = eps (M R2/L2)/(n_p psi)`` (mechanical rad/s per A, ``eps = R2_hat/R2 - 1``), and the
speed loop's plant becomes ``k_t k/(J s) - g``: a right-half-plane zero at
``z = k_t k/(g J)`` (``k`` the field weakening's flux factor, ``k_t`` the rated flux's torque
constant). With the PI's proportional gain ``kp_w`` the loop rings where ``kp_w g``
approaches 1, and ``kp_w g = J a_s eps R2/(1.5 n_p^2 psi psi_rated)`` grows as ``1/k``:
on Table IV from R2_hat = 1.3 R2 it is 0.41 at rated flux and 0.95 at twice the rated speed
(``psi`` 0.19 of 0.46 Wb), where the drive limit-cycled at 6 Hz (the 5 Hz speed loop),
``i_q*`` swinging +-16 A at no load and the estimate off by -6 rpm per ampere as the formula
says; the compensator's transient gate then held R2_hat for the whole run.

Scaled by the flux factor, ``kp_w k`` and ``ki_w k^2``, the product ``kp_w g`` keeps its
rated-flux value at any depth of field weakening, and the loop keeps its shape: its crossover
``a_s k^2`` and the PI's zero ``a_s k/4`` keep their ratio (the phase margin), both slower by
``k``. At rated flux (``fw_cut = 0``) the gains are the designed ones, bit for bit.

The loop's gain over the rated flux's, ``k`` (the torque constant) times ``k`` again with the
scaled gains (:func:`speed_loop_gain`), is what the compensator's transient gate divides its
speed threshold by: after any event (an R2_hat step moves the estimate by ``eps`` of the slip,
a torque step) the speed error's area is the event over the loop's gain, ``1/k^2`` times
its rated-flux value with the scaled gains. With the unscaled threshold (1 rpm on Table IV)
each of the compensator's own steps at twice the rated speed (``k`` 0.38, the loop's
crossover 0.7 Hz) left a mean speed error above it for the next decision and the hold after
it: R2_hat was frozen 75 % of the time from R2_hat(0) = 0.7 R2 and lagged a heating ramp by
6.4 % at its end.
"""

from __future__ import annotations

from imdrive.kernels.jit import njit


@njit(cache=True)
def speed_pi_gains(p, s):
    """The speed PI's gains this period: ``(kp_w, ki_w)`` of ``p`` (CONTROL_PARAMS), times
    ``k`` and ``k^2`` with ``p.w_fw_sched`` and the flux factor ``k = 1 - s.fw_cut < 1``
    (CONTROL_STATE), A/(rad/s) and A/rad (module docstring)."""
    if p.w_fw_sched and s.fw_cut > 0.0:
        k = 1.0 - s.fw_cut
        return p.kp_w * k, p.ki_w * k * k
    return p.kp_w, p.ki_w


@njit(cache=True)
def speed_loop_gain(p, k):
    """The speed loop's gain over its rated-flux value (dimensionless, <= 1): the torque
    constant's flux factor ``k = 1 - fw_cut`` (CONTROL_STATE), times ``k`` again with
    ``p.w_fw_sched`` (the PI's proportional gain scaled by :func:`speed_pi_gains`); 1 at
    rated flux. The speed error's area after a disturbance scales with its inverse (module
    docstring)."""
    if k < 1.0:
        return k * k if p.w_fw_sched else k
    return 1.0
