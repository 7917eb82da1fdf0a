"""Replay: a registered speed estimator run open loop on recorded signals.

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

Both functions release the GIL (``nogil``): the estimators of one chunk run in parallel
threads, each on its own records and output arrays, reading the same rows.
"""

from __future__ import annotations

import cmath
import math

from numba import njit

from imdrive.kernels.estimators.registry import (
    EstimatorInput,
    estimator_finite,
    estimator_step,
)
from imdrive.kernels.records import b1, c16, f8, record_dtype

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
    ]
)

#: :func:`replay_estimator`'s status: every row replayed, or a state not finite.
R_OK = 0
R_NAN = 1


@njit(cache=True, nogil=True)
def fill_rows(rows, t, i_a, i_b, v_a, v_b, ctx, model, prev):
    """Build a chunk's :data:`REPLAY_ROW` rows from the recording's columns, in one pass.

    Parameters
    ----------
    rows : REPLAY_ROW[n]
        Filled (every field).
    t, i_a, i_b, v_a, v_b : float64[n]
        ``time_s``, ``i_alpha_meas_A``, ``i_beta_meas_A``, ``v_alpha_cmd_V``,
        ``v_beta_cmd_V``.
    ctx : float64[8, n] or float64[8, 1]
        The context: ``theta_e_rad``, ``w_e_rad_s``, ``id_ref_A``, ``iq_ref_A``,
        ``w_ref_rad_s``, ``i_inj_A``, ``hold_R1_flag``, ``restart_flag``; a row of length 1
        is a constant (a column the recording lacks, at its default).
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


@njit(cache=True, nogil=True, error_model="numpy")
def replay_estimator(pe, mdl, est, rows, Ts, model_given, w_out, R2_out):
    """Run one estimator over the recording's ``rows`` (its records updated in place).

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
    for k in range(rows.shape[0]):
        r = rows[k]
        if model_given:
            if r.R1_hat != r.R1_prev:  # the controller wrote R1_hat (inverter-error scale)
                m.R1_hat = r.R1_hat
            # R2_hat as the run's controller wrote it (its R2 compensator). This is where an
            # R2-tracking law run on the recording would write its own estimate instead.
            if r.R2_hat != r.R2_prev:
                m.R2_hat = r.R2_hat
            m.M_hat = r.M_hat
        inp = EstimatorInput(
            r.v_ab, r.i_prev_ab, r.i_ab, r.theta_e, r.w_e, r.i_ref_dq, r.w_ref, r.i_inj,
            r.hold_R1, Ts, r.t, r.restart,
        )  # fmt: skip
        w_r_hat, e_dq0 = estimator_step(p, m, s, inp)
        w_out[k] = w_r_hat
        R2_out[k] = m.R2_hat
        ok = math.isfinite(w_r_hat) and cmath.isfinite(e_dq0) and estimator_finite(s)
        if not ok:
            return R_NAN, k + 1
    return R_OK, rows.shape[0]
