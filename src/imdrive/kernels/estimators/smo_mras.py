"""Sliding-mode MRAS speed estimator (``control.speed_feedback = "smo-mras"``).

After M. Comanescu and L. Xu, "Sliding-mode MRAS speed estimators for sensorless vector
control of induction machine", IEEE Trans. Industrial Electronics 53(1), p. 146, 2006: the
rotor flux of the voltage model is the reference, the current model is made a sliding-mode
flux observer whose speed input is a discontinuous control driven by the flux error, and the
speed estimate is that control's *equivalent* value (its low-frequency content), extracted by
a low-pass filter -- an algebraic result in place of Schauder's PI adaptation law. (Only
the paper's abstract was at hand when this module was written: the structure above is what
it states; the equations below are this project's rendering of it, and the items marked
*this project's* are not claimed to be the paper's.)

Reference model (voltage model, Park et al. eq. 1), as in :mod:`.mras` with Schauder's
``1/(s + wc)`` in place of the pure integrator::

    p lam = (L2/M) (v - R1 i - sigma L1 p i)

Adjustable model (current model, Park et al. eq. 2) with the switching control ``u`` as its
speed, passed through the same ``s/(s + wc)`` so the two outputs stay comparable::

    p lam_hat = (-1/T2_hat + j u) lam_hat + (M/T2_hat) i

Sliding variable: the MRAS error (Park et al. eq. 9) normalised by the adjustable model's flux
magnitude, so that it is the angle (rad) by which the reference flux leads the adjustable one
whatever the flux level::

    sigma = (lam_q lam_hat_d - lam_d lam_hat_q) / max(|lam_hat|^2, psi2_min)  ~  delta

Linearised about ``lam_hat = lam`` the angle obeys ``p delta = w_r - u`` plus a term of the
flux-magnitude error that decays with the rotor time constant, so ``u = W sgn(sigma)`` with
``W > |w_r - (centre)|`` reaches ``sigma = 0`` in finite time and holds it; on the surface
``p sigma = 0`` and the equivalent control is ``u_eq = w_r`` (Utkin's equivalent control,
V. I. Utkin, *Sliding Modes in Control and Optimization*, Springer 1992, ch. 2).

Switching law and equivalent control (the paper's structure; the parts below marked
*this project's* are not the paper's)::

    u       = w_r_hat + W sat(sigma / phi)                   (adjustable model's speed)
    w_r_hat = u / (1 + s / w_f)                               (equivalent control, output)

* *This project's*: the switching term is centred on the present equivalent-control estimate
  ``w_r_hat`` instead of zero, so the switching gain ``W`` only has to exceed the largest
  *speed error* to be tracked (``|w_r - w_r_hat|``, the filter's lag in a ramp or a load
  transient), not the largest speed; since ``w_r_hat`` is the low-pass of ``u``,
  ``p w_r_hat = w_f W sat(sigma/phi)``: the filter is an integral action on the switching
  term, and in sliding ``w_r_hat`` follows ``w_r`` as a first-order lag of bandwidth ``w_f``;
  a speed step larger than ``W`` is first slewed at ``w_f W`` (rad/s^2) until the error is
  below ``W``.
* *This project's*: the boundary layer ``sat(x) = min(max(x, -1), 1)`` of width ``phi``
  (rad), the classic remedy for chattering (J.-J. E. Slotine and W. Li, *Applied Nonlinear
  Control*, Prentice Hall 1991, section 7.2). In discrete time the relay moves the adjustable
  flux by ``W Ts`` rad per period; inside the layer the law is linear with loop gain
  ``W Ts / phi`` per period (the default ``phi = 2 W Ts`` gives 0.5, no period-2 chatter).
  ``phi = 0`` is the pure relay ``sgn(sigma)`` (``sgn(0) = 0``).
* *This project's*: the normalisation of sigma (an angle), the discretisation (below) and the
  gain design (:class:`imdrive.config.estimators.SmoMrasSettings`).

Discretisation at the control period Ts, as :mod:`.mras`: the voltage model's increment from
the held voltage and the two current samples, the current model exact over the period for
the switching control ``u`` held over it and a current varying linearly between its samples
(:func:`imdrive.kernels.estimators.common.current_model_step`), the common filter exact for a
derivative constant over the period, and the equivalent-control filter exact for ``u`` held
over the period: ``w_r_hat += (1 - exp(-w_f Ts)) (u - w_r_hat)``. The ``u`` computed at a
sample is applied to the current model over the next period.

The flux error returned (``e_dq0``, reference minus adjustable in the controller's frame) is
the MRAS's, so the R2 compensator can run on it.
"""

from __future__ import annotations

import cmath
import math

from imdrive.kernels.estimators.common import (
    current_model_step,
    lowpass_coefficients,
    period_mean_offset,
)
from imdrive.kernels.estimators.registry import register_kernel
from imdrive.kernels.jit import njit
from imdrive.kernels.model import model_inductances
from imdrive.kernels.records import b1, c16, f8, record_dtype

#: Parameters (from :class:`imdrive.config.estimators.SmoMrasSettings`).
SMO_MRAS_PARAMS = record_dtype(
    [
        ("wc", f8),  # cut-off of the low-pass replacing the integrators, rad/s (0: pure)
        ("W", f8),  # switching gain: the largest speed error held in sliding, electrical rad/s
        ("phi", f8),  # boundary layer of the sliding variable, rad (0: pure sign function)
        ("w_f", f8),  # bandwidth of the equivalent-control low-pass, rad/s
        ("psi2_min", f8),  # floor of |lam_hat|^2 in the normalisation of sigma, Wb^2
        ("bend", b1),  # the current model gets the current's mean over the period
    ]
)

#: State.
SMO_MRAS_STATE = record_dtype(
    [
        ("lam_v_ab", c16),  # reference (voltage) model rotor flux, filtered, Wb
        ("lam_i_ab", c16),  # adjustable (current) model rotor flux, unfiltered, Wb
        ("lam_f_ab", c16),  # adjustable model passed through the same filter, Wb
        ("u", f8),  # switching control: the adjustable model's speed, electrical rad/s
        ("w_r_hat", f8),  # equivalent control: the speed estimate, electrical rad/s
        ("sigma", f8),  # sliding variable (flux angle error), rad
        ("e_dq0", c16),  # flux error (reference - adjustable) in the controller's frame, Wb
    ]
)

#: Own log fields: the sliding variable (rad) and the switching control (mechanical rad/s).
LOG_FIELDS = ("smo_sigma", "smo_u")


@njit(cache=True)
def voltage_model_increment(m, v_ab, i_prev_ab, i_ab, Ts):
    """Change of the voltage-model rotor flux over one period, Wb (complex, stationary frame).

    ``(L2/M) [Ts (v - R1 i_mean) - sigma L1 (i_k - i_{k-1})]`` (Park et al. eq. 1 integrated
    over the period, the voltage held, the current the mean of its end samples), as in
    :func:`imdrive.kernels.estimators.mras.mras_step`, but without the saturating model's
    terms the MRAS adds (:func:`~imdrive.kernels.estimators.common.saturation_increment`):
    with them, on the realistic drive (``imdrive.bench.docs``) the sliding-mode MRAS lost
    control in 3 of 10 cases instead of 1 (30 rpm at rated load, and with R̂1 off; measured
    2026-11-30): its switching control moves the speed, the torque current and with it M̂ every
    period, and the terms pass that on.

    Parameters
    ----------
    m : MODEL_STATE record
        The controller's machine model (``R1_hat`` in ohm, inductances in H).
    v_ab : complex
        Voltage applied over the period, V.
    i_prev_ab, i_ab : complex
        Stator current at the start and at the end of the period, A.
    Ts : float
        Period, s.
    """
    M, L1, L2, sigma_L1 = model_inductances(m)
    R1 = m.R1_hat
    kv = L2 / M
    i_mean_a = 0.5 * (i_ab.real + i_prev_ab.real)
    i_mean_b = 0.5 * (i_ab.imag + i_prev_ab.imag)
    d_a = kv * (Ts * (v_ab.real - R1 * i_mean_a) - sigma_L1 * (i_ab.real - i_prev_ab.real))
    d_b = kv * (Ts * (v_ab.imag - R1 * i_mean_b) - sigma_L1 * (i_ab.imag - i_prev_ab.imag))
    return complex(d_a, d_b)


@njit(cache=True)
def switching(sigma, phi):
    """The switching function: ``sgn(sigma)`` if ``phi == 0``, else ``sat(sigma / phi)``.

    Parameters
    ----------
    sigma : float
        Sliding variable, rad.
    phi : float
        Boundary-layer width, rad (>= 0).
    """
    if phi > 0.0:
        return min(max(sigma / phi, -1.0), 1.0)
    if sigma > 0.0:
        return 1.0
    if sigma < 0.0:
        return -1.0
    return 0.0


@njit(cache=True)
def smo_mras_estimate(p, m, s, inp):
    """Advance the sliding-mode MRAS by one period (module docstring; updates ``s``).

    Parameters
    ----------
    p : SMO_MRAS_PARAMS record
    m : MODEL_STATE record
        The controller's machine model (``R1_hat``, ``R2_hat`` in ohm; inductances in H).
    s : SMO_MRAS_STATE record
        Updated in place.
    inp : ESTIMATOR_INPUT record
        ``v_ab`` (V), ``i_prev_ab``, ``i_ab`` (A), ``theta_e`` (rad), ``Ts`` (s).

    Returns
    -------
    w_r_hat : float
        Speed estimate (the equivalent control), electrical rad/s.
    e_dq0 : complex
        Rotor-flux error, reference minus adjustable model, in the controller's frame, Wb.
    """
    M, L1, L2, sigma_L1 = model_inductances(m)
    Ts = inp.Ts
    wc = p.wc
    g, k_in = lowpass_coefficients(wc, Ts)

    # reference (voltage) model through 1/(s + wc)
    d = voltage_model_increment(m, inp.v_ab, inp.i_prev_ab, inp.i_ab, Ts)
    lam_v_a = g * s.lam_v_ab.real + k_in * d.real
    lam_v_b = g * s.lam_v_ab.imag + k_in * d.imag

    # adjustable (current) model driven by the switching control held over the period
    # (the current's mean over the period: its samples' plus the back-emf's bend)
    i0 = inp.i_prev_ab
    i1 = inp.i_ab
    i_bend = 0j
    if p.bend:
        i_bend = period_mean_offset(
            s.lam_i_ab, s.u, m.R1_hat, m.R2_hat, L2, M, sigma_L1, i0, i1, Ts
        )
    lam_new = current_model_step(s.lam_i_ab, s.u, m.R2_hat, L2, M, i0 + i_bend, i1 + i_bend, Ts)
    dlam = lam_new - s.lam_i_ab
    lam_f_a = g * s.lam_f_ab.real + k_in * dlam.real
    lam_f_b = g * s.lam_f_ab.imag + k_in * dlam.imag

    # equivalent control: the low-pass of the control applied over the period just ended
    a = 1.0 - math.exp(-p.w_f * Ts)
    w_hat = s.w_r_hat + a * (s.u - s.w_r_hat)

    # sliding variable (the flux angle error, rad) and the switching law for the next period
    lam2 = lam_f_a * lam_f_a + lam_f_b * lam_f_b
    sigma = (lam_v_b * lam_f_a - lam_v_a * lam_f_b) / max(lam2, p.psi2_min)
    s.u = w_hat + p.W * switching(sigma, p.phi)
    s.w_r_hat = w_hat
    s.sigma = sigma

    # flux error (reference minus adjustable) in the controller's synchronous frame
    cs = math.cos(inp.theta_e)
    sn = math.sin(inp.theta_e)
    err_a = lam_v_a - lam_f_a
    err_b = lam_v_b - lam_f_b
    s.e_dq0 = complex(cs * err_a + sn * err_b, -sn * err_a + cs * err_b)

    s.lam_v_ab = complex(lam_v_a, lam_v_b)
    s.lam_i_ab = lam_new
    s.lam_f_ab = complex(lam_f_a, lam_f_b)
    return w_hat, s.e_dq0


@njit(cache=True)
def log_smo_mras(row, p, s, n_p):
    """Write :data:`LOG_FIELDS`: ``smo_sigma`` (rad), ``smo_u`` (mechanical rad/s)."""
    row.smo_sigma = s.sigma
    row.smo_u = s.u / n_p


@njit(cache=True)
def smo_mras_finite(s):
    """Whether every state of the sliding-mode MRAS is finite."""
    c = cmath.isfinite
    ok = c(s.lam_v_ab) and c(s.lam_i_ab) and c(s.lam_f_ab) and c(s.e_dq0)
    return ok and math.isfinite(s.u) and math.isfinite(s.w_r_hat) and math.isfinite(s.sigma)


KERNEL = register_kernel(
    "smo-mras",
    SMO_MRAS_PARAMS,
    SMO_MRAS_STATE,
    smo_mras_estimate,
    log_fields=LOG_FIELDS,
    log=log_smo_mras,
    finite=smo_mras_finite,
)
