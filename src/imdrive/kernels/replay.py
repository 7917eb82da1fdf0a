"""Replay: a registered speed estimator, and the R2 law, run open loop on recorded signals.

The closed loop hands its estimator, each control period, an
:class:`~imdrive.kernels.estimators.registry.EstimatorInput` and the controller's machine
model (:data:`~imdrive.kernels.model.MODEL_STATE`), and calls it through the registry's
generic :func:`~imdrive.kernels.estimators.registry.estimator_step`.
:func:`replay_estimator` does the same from the rows of a recording (:data:`REPLAY_ROW`,
built by :mod:`imdrive.run.replay` from a recording file), so any registered estimator,
a user's own included, replays through the code path it runs in the closed loop; numba
compiles the loop once per estimator (the registry dispatches on the type of its records) and
caches it.

The controller's model
----------------------
The estimator reads the model and may adapt ``R1_hat``/``R2_hat`` in it. In the closed loop
the controller writes it too, between two estimator steps: the R2 compensator ``R2_hat``, the
inverter-error scale ``R1_hat``, the magnetising curve ``M_hat``. A recording that carries the
model (``model_given``) gives, for each row, the values the run's estimator read and those it
left after its step (``R1_prev``/``R2_prev``: the previous row's); where they differ the
controller wrote the model in between, and the replay writes the recorded value into the
replayed estimator's model; where they agree the replayed estimator keeps its own (its own
adaptation carries on). ``M_hat`` is the controller's alone: it is taken as recorded. With the
run's own estimator this reproduces the closed loop's model exactly; a recording without the
model leaves the estimator the scenario's, adapted by itself alone.

The R2 law
----------
Where the replay runs the scenario's R2 law (``trk``'s ``law``), each estimator carries a
compensator of its own and calls :func:`~imdrive.kernels.r2_tracking.excitation` before its
step and :func:`~imdrive.kernels.r2_tracking.track` after it, as the closed loop does, with
the :class:`~imdrive.kernels.r2_tracking.TrackingInput` built from the recorded context; the
law, not the recording, then writes ``R2_hat``. The estimator reads the injected current the
recording holds (what the drive injected); the law's detection demodulates with its own
phase, and the largest difference of its injection from the recorded one is kept: a
scenario whose injection is not the recorded drive's shows there. The law's gate watches
the drive's transients, so it reads the recorded speed loop's feedback, not the replayed
estimate (which differs from it by the two estimators' disagreement, and held the EKF's law
on the Aalto machine for the whole replay: R2_hat stayed 20 % off).

Both functions release the GIL (``nogil``): the estimators of one chunk run in parallel
threads, each on its own records and output arrays, reading the same rows.
"""

from __future__ import annotations

import cmath
import math

from imdrive.kernels.estimators.registry import (
    EstimatorInput,
    estimator_finite,
    estimator_step,
)
from imdrive.kernels.jit import njit
from imdrive.kernels.r2_tracking import TrackingInput, excitation, track
from imdrive.kernels.records import b1, c16, f8, record_dtype
from imdrive.kernels.speed_control import speed_loop_gain

#: One period of a replay: the estimator's input and the controller's model (SI units).
REPLAY_ROW = record_dtype(
    [
        ("t", f8),  # the sample t_k, s
        ("v_ab", c16),  # the voltage commanded over the last period, V
        ("i_prev_ab", c16),  # the current sampled at the last sample, A
        ("i_ab", c16),  # the current sampled now, A
        ("theta_e", f8),  # the controller's angle, rad
        ("w_e", f8),  # the controller's stator frequency, electrical rad/s
        ("i_ref_dq", c16),  # the current references of the last period, A
        ("w_ref", f8),  # the speed reference, mechanical rad/s
        ("i_inj", f8),  # the R2 compensator's injected d-axis current, A
        ("hold_R1", b1),  # the R1 adaptation held
        ("restart", b1),  # the standstill R1 test set R1_hat at the last sample
        ("R1_hat", f8),  # the model the run's estimator read, ohm (model_given)
        ("R2_hat", f8),
        ("M_hat", f8),  # H
        ("R1_prev", f8),  # the model the run's estimator left at the last sample, ohm
        ("R2_prev", f8),
        # what the R2 law reads of the controller besides (kernels/r2_tracking.py)
        ("t_hold", f8),  # the standstill test's hold of the duty cycle, s
        ("v_use", f8),  # the last commanded voltage over Vdc_meas/sqrt 3
        ("k_flux", f8),  # the field weakening's flux factor
        ("w_sl", f8),  # the slip command, electrical rad/s
        ("iq_meas", f8),  # the measured torque current of the last control period, A
        ("L_inc_hat", f8),  # the model's incremental magnetising inductance, H (0: not given)
        ("w_fb", f8),  # the speed loop's feedback, mechanical rad/s (NaN: not given)
        ("w_m", f8),  # the encoder's speed, mechanical rad/s (0 without one)
    ]
)

#: :func:`replay_estimator`'s status: every row replayed, or a state not finite.
R_OK = 0
R_NAN = 1


@njit(cache=True, entry=True, nogil=True)
def fill_rows(rows, t, i_a, i_b, v_a, v_b, ctx, model, prev):
    """Build a chunk's :data:`REPLAY_ROW` rows from the recording's columns, in one pass.

    Parameters
    ----------
    rows : REPLAY_ROW[n]
        Filled (every field).
    t, i_a, i_b, v_a, v_b : float64[n]
        ``time_s``, ``i_alpha_meas_A``, ``i_beta_meas_A``, ``v_alpha_cmd_V``,
        ``v_beta_cmd_V``.
    ctx : float64[16, n] or float64[16, 1]
        The context: ``theta_e_rad``, ``w_e_rad_s``, ``id_ref_A``, ``iq_ref_A``,
        ``w_ref_rad_s``, ``i_inj_A``, ``hold_R1_flag``, ``restart_flag``, ``t_hold_s``,
        ``v_use_pu``, ``k_flux_pu``, ``w_sl_rad_s``, ``iq_meas_A``, ``L_inc_hat_H``,
        ``w_fb_rad_s`` and the encoder's speed,
        mechanical rad/s; a row of length 1 is a constant (a column the recording lacks, at
        its default).
    model : float64[5, n] or float64[5, 0]
        ``R1_hat_ohm``, ``R2_hat_ohm``, ``M_hat_H``, ``R1_hat_after_ohm``,
        ``R2_hat_after_ohm``; empty where the recording lacks the model (those fields zero).
    prev : complex128[4]
        The row before the chunk: its current, its voltage, its ``R1_hat_after`` and
        ``R2_hat_after`` (real parts; NaN before the first row); updated to the chunk's last.

    Notes
    -----
    Row k's voltage is the one commanded at t_{k-1}, for the period that ends at t_k; its
    ``i_prev_ab`` the current sampled at t_{k-1}.
    """
    n = rows.shape[0]
    nc = ctx.shape[1]
    given = model.shape[1] > 0
    i_last = prev[0]
    v_last = prev[1]
    R1_last = prev[2].real
    R2_last = prev[3].real
    for k in range(n):
        r = rows[k]
        c = k if nc > 1 else 0
        i_ab = complex(i_a[k], i_b[k])
        r.t = t[k]
        r.i_ab = i_ab
        r.i_prev_ab = i_last
        r.v_ab = v_last
        i_last = i_ab
        v_last = complex(v_a[k], v_b[k])
        r.theta_e = ctx[0, c]
        r.w_e = ctx[1, c]
        r.i_ref_dq = complex(ctx[2, c], ctx[3, c])
        r.w_ref = ctx[4, c]
        r.i_inj = ctx[5, c]
        r.hold_R1 = ctx[6, c] != 0.0
        r.restart = ctx[7, c] != 0.0
        r.t_hold = ctx[8, c]
        r.v_use = ctx[9, c]
        r.k_flux = ctx[10, c]
        r.w_sl = ctx[11, c]
        r.iq_meas = ctx[12, c]
        r.L_inc_hat = ctx[13, c]
        r.w_fb = ctx[14, c]
        r.w_m = ctx[15, c]
        if given:
            r.R1_hat = model[0, k]
            r.R2_hat = model[1, k]
            r.M_hat = model[2, k]
            r.R1_prev = R1_last
            r.R2_prev = R2_last
            R1_last = model[3, k]
            R2_last = model[4, k]
        else:
            r.R1_hat = 0.0
            r.R2_hat = 0.0
            r.M_hat = 0.0
            r.R1_prev = 0.0
            r.R2_prev = 0.0
    prev[0] = i_last
    prev[1] = v_last
    prev[2] = R1_last
    prev[3] = R2_last


@njit(cache=True, entry=True, nogil=True, error_model="numpy")
def replay_estimator(pe, mdl, est, rows, Ts, model_given, w_out, R2_out, trk, k0):
    """Run one estimator, and the R2 law where ``trk`` says so, over the recording's
    ``rows`` (the records updated in place).

    Parameters
    ----------
    pe : the estimator's params record array, (1,)
    mdl : MODEL_STATE[1]
        The controller's model, at the state of the first row (updated).
    est : the estimator's state record array, (1,)
        At the state of the first row (updated): consecutive calls on consecutive chunks
        reproduce one call on the whole recording.
    rows : REPLAY_ROW[n]
    Ts : float
        The control period the estimator integrates over, s.
    model_given : bool
        Whether ``rows`` carry the controller's model (module docstring).
    w_out : float64[n]
        Receives the speed estimate after each row, electrical rad/s.
    R2_out : float64[n]
        Receives the model's ``R2_hat`` after each row, ohm.
    trk : tuple
        ``(law, pk, cmp, table, pc, sensorless, n_p, inj_err)``: whether the R2 law runs
        (it then writes ``R2_hat``, not the recording), the compensator's params and state
        record arrays (state updated), its decision table, the control params record array,
        whether the drive's speed feedback is the estimate (the gate's speed) and the pole
        pairs; ``inj_err`` (float64[1]) keeps the largest difference of the law's injected
        current from the recorded one, A.
    k0 : int
        Rows replayed before these (the sample index of the first, the law's decision
        periods count from the recording's first row).

    Returns
    -------
    status : int
        ``R_OK`` or ``R_NAN`` (the estimate or the estimator's state not finite).
    k_end : int
        Rows replayed (the row where a state stopped being finite, counted).
    """
    p = pe[0]
    m = mdl[0]
    s = est[0]
    law, pk_a, cmp_a, table, pc_a, sensorless, n_p, inj_err = trk
    pk = pk_a[0]
    cmp = cmp_a[0]
    pc = pc_a[0]
    for k in range(rows.shape[0]):
        r = rows[k]
        if model_given:
            if r.R1_hat != r.R1_prev:  # the controller wrote R1_hat (inverter-error scale)
                m.R1_hat = r.R1_hat
            # R2_hat as the run's R2 law wrote it, where the replay does not run the law
            if not law and r.R2_hat != r.R2_prev:
                m.R2_hat = r.R2_hat
            m.M_hat = r.M_hat
        if r.L_inc_hat > 0.0:  # the controller's magnetising curve, where recorded
            m.L_inc_hat = r.L_inc_hat
        t_cyc = r.t - r.t_hold
        sine = 0.0
        if law:  # the law's excitation, checked against the recorded injection
            sine, i_inj = excitation(pk, cmp, t_cyc, r.v_use, r.k_flux, Ts)
            inj_err[0] = max(inj_err[0], abs(i_inj - r.i_inj))
        inp = EstimatorInput(
            r.v_ab, r.i_prev_ab, r.i_ab, r.theta_e, r.w_e, r.i_ref_dq, r.w_ref, r.i_inj,
            r.hold_R1, Ts, r.t, r.restart,
        )  # fmt: skip
        w_r_hat, e_dq0 = estimator_step(p, m, s, inp)
        if law:
            # the gate watches the drive's transients: its speed loop's recorded feedback;
            # without one the closed loop's rule (this estimate, or the encoder)
            w_fb = r.w_fb
            if math.isnan(w_fb):
                w_fb = w_r_hat / n_p if sensorless else r.w_m
            ti = TrackingInput(
                r.t, t_cyc, k0 + k, sine, r.w_ref, w_fb,
                r.i_ref_dq.imag * r.k_flux, r.v_use, r.w_e, r.w_sl,
                speed_loop_gain(pc, r.k_flux), r.iq_meas, Ts,
            )  # fmt: skip
            track(pk, cmp, m, table, e_dq0, inp, w_r_hat, ti)
        w_out[k] = w_r_hat
        R2_out[k] = m.R2_hat
        ok = math.isfinite(w_r_hat) and cmath.isfinite(e_dq0) and estimator_finite(s)
        if not ok:
            return R_NAN, k + 1
    return R_OK, rows.shape[0]
