"""The recording of a closed-loop run: what the controller saw, every control period.

A recording row ``k`` holds what the drive's controller measured and decided at the sample
``t_k`` (the signals a drive's data log holds) and the controller's own values that its speed
estimator read at that sample (the context a replay needs to run the estimator exactly as the
closed loop did, :mod:`imdrive.kernels.replay`):

* signals: the measured current (the estimator's ``i_ab``), the voltage the controller
  commanded at ``t_k`` for the period ``[t_k, t_k + Ts)`` less its inverter-error
  compensation (what it believes reaches the terminals: the estimator's ``v_ab`` at the next
  sample), the rotor's speed (an ideal encoder), the R2 compensator's injected current;
* context: the controller's angle, frequency, current and speed references, whether the R1
  adaptation was held, whether the standstill R1 test has just set ``R1_hat`` (the
  estimator then restarts), and the model's ``R1_hat``, ``R2_hat``, ``M_hat`` as the estimator read
  them and ``R1_hat``, ``R2_hat`` right after its step (so a replay can tell the controller's
  writes to its model, by the R2 compensator or the magnetising curve, from the estimator's
  own adaptation);
* what the R2 law reads of the controller besides: the standstill test's hold of the duty
  cycle, the voltage use, the field weakening's flux factor, the slip command, the measured
  torque current, the model's incremental magnetising inductance, the speed loop's feedback
  (the gate watches the drive's transients, whichever estimator replays)
  (:class:`~imdrive.kernels.r2_tracking.TrackingInput`).

:func:`imdrive.kernels.engine.run_drive` fills it through :func:`record_before` (before the
estimator's step) and :func:`record_after` (once the period's voltage is commanded) when it is
given a ``rec`` array of at least one row per period; with fewer rows (none when not
recording) the rows beyond are not written.
"""

from __future__ import annotations

from imdrive.kernels.jit import njit
from imdrive.kernels.records import b1, c16, f8, record_dtype

#: One row of a recording, SI units (space vectors complex in the stationary frame ``_ab`` or
#: the controller's ``_dq``).
RECORDING = record_dtype(
    [
        ("time", f8),  # the sample t_k, s
        ("i_ab", c16),  # the measured stator current at t_k, A
        ("v_cmd_ab", c16),  # commanded for [t_k, t_k + Ts), less the inverter compensation, V
        ("w_m", f8),  # the rotor's mechanical speed at t_k (an ideal encoder), rad/s
        ("i_inj", f8),  # the R2 compensator's injected d-axis current this period, A
        ("theta_e", f8),  # the controller's d-axis angle at t_k, rad
        ("w_e", f8),  # the controller's stator frequency the estimator read, electrical rad/s
        ("i_ref_dq", c16),  # the current references of the last period, A
        ("w_ref", f8),  # the speed reference, mechanical rad/s
        ("hold_R1", b1),  # the estimator's R1 adaptation held this period
        ("restart", b1),  # the standstill R1 test set R1_hat at the last sample (the input)
        ("R1_hat", f8),  # the controller's model as the estimator read it, ohm
        ("R2_hat", f8),
        ("M_hat", f8),  # H
        ("R1_after", f8),  # R1_hat and R2_hat right after the estimator's step, ohm
        ("R2_after", f8),
        ("w_r_hat", f8),  # the estimator's speed estimate, electrical rad/s
        # what the R2 law reads of the controller besides (kernels/r2_tracking.py)
        ("t_hold", f8),  # the time the standstill R1 test held the duty cycle back, s
        ("v_use", f8),  # the last commanded voltage over Vdc_meas/sqrt 3
        ("k_flux", f8),  # the field weakening's flux factor 1 - fw_cut
        ("w_sl", f8),  # the slip command of the last period, electrical rad/s
        ("iq_meas", f8),  # the measured torque current of the last control period, A
        ("L_inc_hat", f8),  # the model's incremental magnetising inductance, H
        ("w_fb", f8),  # the speed loop's feedback (the estimate or the encoder), mech. rad/s
    ]
)


@njit(cache=True, inline="always")
def record_before(row, smpl, mdl, ctl, smp):
    """Before the estimator's step: the controller's values it reads at this sample."""
    row.time = smpl.t
    row.v_use = smp.v_use
    row.i_ab = smpl.i_meas_ab
    row.theta_e = smpl.theta_k
    row.w_e = ctl.w_e
    row.i_ref_dq = ctl.i_ref_dq
    row.R1_hat = mdl.R1_hat
    row.R2_hat = mdl.R2_hat
    row.M_hat = mdl.M_hat
    row.restart = ctl.dc_restart
    row.t_hold = mdl.t_hold
    row.k_flux = 1.0 - ctl.fw_cut
    row.w_sl = ctl.w_sl
    row.iq_meas = ctl.i_s_dq.imag
    row.L_inc_hat = mdl.L_inc_hat


@njit(cache=True, inline="always")
def record_after(row, x, smp, mdl, prof, estm, foc, w_fb):
    """Once the period's voltage is commanded (``smp.v_prev_ab``, which the next estimator
    step reads): the command, the speed, the estimator's outputs and hold, the speed loop's
    feedback ``w_fb`` (mechanical rad/s)."""
    row.v_cmd_ab = smp.v_prev_ab
    row.w_m = x.w_m
    row.i_inj = estm.i_inj
    row.w_ref = prof.w_ref
    row.hold_R1 = estm.hold_R1
    row.w_r_hat = estm.w_r_hat
    row.w_fb = w_fb
    if foc:
        row.R1_after = estm.R1_after
        row.R2_after = estm.R2_after
    else:  # no estimator ran
        row.R1_after = mdl.R1_hat
        row.R2_after = mdl.R2_hat
