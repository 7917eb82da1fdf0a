"""Reactive-power MRAS speed estimator (Peng & Fukao, IEEE Trans. Ind. Appl. 30(5), 1994).

The model-reference quantity is the reactive power of the magnetising branch, the cross
product of the stator current with the back-emf ``e = (M/L2) p lam``. In the reference model
the back-emf comes from the stator voltage equation; ``i x (R1 i) = 0``, so the stator
resistance drops out and the estimator needs no ``R1`` (its property, checked by a test)::

    q     = i x (v - sigma L1 p i)                     (reference model, no R1, no integrator)
    q_hat = i x (M/L2) p lam_hat                       (adjustable model)
    p lam_hat = (-1/T2_hat + j w_r_hat) lam_hat + (M/T2_hat) i      (current model, eq. 2)

with ``a x b = a_alpha b_beta - a_beta b_alpha``. Adaptation, a PI on the error::

    eps = q - q_hat,         w_r_hat = K1 eps + K2 \\int eps dt

Discretisation at the control period Ts: the voltage over the last period is known (it was
held), the current is taken at the mean of its two samples, and the derivative terms integrate
exactly over the period: ``i_mean x (i_k - i_{k-1}) = i_{k-1} x i_k`` and ``p lam_hat`` averages
to ``(lam_hat_k - lam_hat_{k-1})/Ts`` (current model exact over Ts,
:func:`imdrive.kernels.estimators.common.current_model_step`).

Known limitation (Peng & Fukao's analysis; a finding of the bench, not a bug): the steady-state
sensitivity of ``eps`` to a speed error is proportional to ``w_e w_slip`` (see
:func:`imdrive.design.estimators.default_reactive_mras_gains`), so it vanishes at no load and
changes sign in regeneration.
"""

from __future__ import annotations

import numpy as np

from imdrive.kernels.estimators.common import current_model_step, to_frame
from imdrive.kernels.estimators.registry import ReducedState, register_kernel
from imdrive.kernels.jit import njit
from imdrive.kernels.model import model_inductances
from imdrive.kernels.records import c16, f8, record_dtype

#: Parameters (gains from :func:`imdrive.design.estimators.default_reactive_mras_gains`).
REACTIVE_MRAS_PARAMS = record_dtype(
    [
        ("K1", f8),  # proportional adaptation gain, (rad/s)/var per (A V)
        ("K2", f8),  # integral adaptation gain, (rad/s^2)/(A V)
    ]
)

#: State.
REACTIVE_MRAS_STATE = record_dtype(
    [
        ("lam_ab", c16),  # adjustable (current) model rotor flux, Wb
        ("q_ref", f8),  # reference reactive quantity over the last period, A V
        ("q_hat", f8),  # adjustable-model reactive quantity, A V
        ("int_e", f8),  # integral of the error, A V s
        ("w_r_hat", f8),  # speed estimate, electrical rad/s
    ]
)


@njit(cache=True)
def reactive_mras_step(
    p, m, s, v_prev_alpha, v_prev_beta, i_prev_alpha, i_prev_beta, i_alpha, i_beta, Ts
):
    """Advance the reactive-power MRAS by one control period (updates ``s``).

    Parameters
    ----------
    p : REACTIVE_MRAS_PARAMS record
    m : MODEL_STATE record
        The controller's machine model (``R2_hat``, inductances; ``R1_hat`` is not used).
    s : REACTIVE_MRAS_STATE record
        Updated in place; ``w_r_hat`` is the electrical speed estimate, rad/s.
    v_prev_alpha, v_prev_beta : float
        Voltage applied over the period that just ended, V.
    i_prev_alpha, i_prev_beta, i_alpha, i_beta : float
        Stator current at the previous and at this sample, A.
    Ts : float
        Control period, s.
    """
    M, L1, L2, sigma_L1 = model_inductances(m)
    R2 = m.R2_hat
    i_m_alpha = 0.5 * (i_alpha + i_prev_alpha)
    i_m_beta = 0.5 * (i_beta + i_prev_beta)
    # reference model: i x v - sigma L1 (i x p i); i_mean x (i1 - i0) = i0 x i1
    q_ref = i_m_alpha * v_prev_beta - i_m_beta * v_prev_alpha
    q_ref -= sigma_L1 * (i_prev_alpha * i_beta - i_prev_beta * i_alpha) / Ts
    # adjustable model
    lam_old = s.lam_ab
    lam_new = current_model_step(
        lam_old,
        s.w_r_hat,
        R2,
        L2,
        M,
        complex(i_prev_alpha, i_prev_beta),
        complex(i_alpha, i_beta),
        Ts,
    )
    de = (M / L2) * (lam_new - lam_old) / Ts
    q_hat = i_m_alpha * de.imag - i_m_beta * de.real
    # adaptation
    e = q_ref - q_hat
    s.int_e += Ts * e
    s.w_r_hat = p.K1 * e + p.K2 * s.int_e
    s.lam_ab = lam_new
    s.q_ref = q_ref
    s.q_hat = q_hat


@njit(cache=True)
def reactive_mras_estimate(p, m, s, inp):
    """The reactive-power MRAS in the estimator contract; it has no flux error (``0j``)."""
    v = inp.v_ab
    i0 = inp.i_prev_ab
    i1 = inp.i_ab
    reactive_mras_step(p, m, s, v.real, v.imag, i0.real, i0.imag, i1.real, i1.imag, inp.Ts)
    return s.w_r_hat, 0j


# --- its states in the stability maps' reduced drive state (kernels/linearise.py) ----------

#: The adjustable model's flux, the adaptation's integral and the speed estimate (the next
#: period's model runs at it), controller's frame; ``q_ref``, ``q_hat`` are not read again.
REDUCED_NAMES = ("lam_d", "lam_q", "int_e", "w_r_hat")
REDUCED_SCALE = (0.1, 0.1, 1e-2, 1.0)


@njit(cache=True)
def reactive_mras_reduce(p, s, c, z, k):
    """Its states into ``z[k:k + 4]`` (``ReducedState.reduce``)."""
    z[k], z[k + 1] = to_frame(c, s.lam_ab)
    z[k + 2] = s.int_e
    z[k + 3] = s.w_r_hat


@njit(cache=True)
def reactive_mras_restore(z, k, s):
    """``z[k:k + 4]`` back into its state (``ReducedState.restore``)."""
    s.lam_ab = complex(z[k], z[k + 1])
    s.int_e = z[k + 2]
    s.w_r_hat = z[k + 3]


def reactive_mras_steady(c, p, I, w_e, w_r_hat):
    """Its states at rest: the current model's flux at the estimate, ``M_hat I / (1 + j (w_e -
    w_r_hat) T2_hat)``, and the integral ``w_r_hat / K2`` (no error)."""
    lam = c["M_hat"] * I / (1.0 + 1j * (w_e - w_r_hat) * (c["L2_hat"] / c["R2_hat"]))
    k2 = float(p["K2"])
    return np.column_stack([lam.real, lam.imag, w_r_hat / k2 if k2 != 0 else 0 * w_r_hat, w_r_hat])


KERNEL = register_kernel(
    "reactive-mras",
    REACTIVE_MRAS_PARAMS,
    REACTIVE_MRAS_STATE,
    reactive_mras_estimate,
    reduced=ReducedState(
        REDUCED_NAMES,
        REDUCED_SCALE,
        reactive_mras_reduce,
        reactive_mras_restore,
        reactive_mras_steady,
    ),
)
