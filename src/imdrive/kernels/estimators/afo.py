"""Adaptive full-order flux observer (Kubota, Matsuse & Nakano, IEEE Trans. Ind. Appl. 29(2),
1993), with an observer gain for stable low-speed regeneration, optional R1 adaptation (Kubota
et al. 1993) and R2 adaptation under flux-command injection (Kubota & Matsuse, IEEE Trans. Ind.
Appl. 30(5), 1994).

Machine model, stationary frame, state ``(i, lam)`` (stator current, rotor flux)::

    sigma L1 p i = v - R_sigma i + k (1/T2 - j w_r) lam,      k = M/L2,  R_sigma = R1 + k^2 R2
    p lam        = (M/T2) i - (1/T2 - j w_r) lam,            T2 = L2/R2

Observer (hats: the model's values and the estimated speed), correction by the current error
``e = i - i_hat`` held over the period::

    p i_hat   = (the model above at i_hat, lam_hat, w_r_hat) + g1 e
    p lam_hat = (the model above at i_hat, lam_hat, w_r_hat) + g2 e

Speed adaptation (Kubota et al. 1993, eq. 17)::

    eps = Im(conj(e) lam_hat) = e_alpha lam_hat_beta - e_beta lam_hat_alpha
    w_r_hat = Kp eps + Ki \\int eps dt

(``Kp`` and ``Ki`` both scaled by :func:`adaptation_share` at low stator frequency.)

**Observer gain.** With ``g1 = g2 = 0`` the steady-state sensitivity of ``eps`` to a speed
error ``w_r - w_r_hat`` is proportional to ``w_e Im D``, ``D`` as in
:func:`imdrive.design.estimators.afo_dc_sensitivity`, and with no gain::

    Im D = w_s R1 + w_e (sigma L1/T2 + k^2 R2)            (w_e stator, w_s slip frequency)

which changes sign in regeneration (``w_e w_s < 0``) below ``|w_e| = |w_s| R1 / (sigma L1/T2 +
k^2 R2)``: the adaptation then drives the estimate away (the known unstable region of the
plain observer). Following the approach of Hinkkanen & Luomi (IEEE Trans. Ind. Electron.
51(6), 2004) -- choose the gain so that this sensitivity keeps the sign of ``w_e`` at every
slip -- the gain here cancels (``rho = 1``) or shrinks (``rho < 1``) the slip term of
``Im D``::

    g2 = -rho (R1_hat + sigma L1 g1) / k,     g1 >= 0 free (default 0), rho = 0.9

``rho = 1`` gives ``Im D = w_e (sigma L1/T2 + R_sigma)`` but leaves the flux error undamped at
zero stator frequency (the flux equation becomes the pure voltage model); ``rho = 0.9`` keeps
some damping and shrinks the unstable band tenfold
(:func:`imdrive.design.estimators.afo_regeneration_gain`). The closed form is derived in this
project, not Hinkkanen & Luomi's published expression; its linearised stability (error
dynamics with the speed adaptation) is checked by a test. ``gain_mode = 2`` (the default)
schedules ``rho`` with the operating point (:func:`scheduled_rho`): no more than the band's
edge at the observer's stator frequency needs, so 0 in motoring, where the plain observer is
stable and damps best. ``gain_mode = 0`` uses ``g1``, ``g2`` as given.

**R1 adaptation** (Kubota et al. 1993, eq. 19): ``p R1_hat = -k_R1 Re(conj(e) i_hat)``.
**R2 adaptation** (after Kubota & Matsuse 1994): ``p R2_hat = k_R2 Re(conj(e) d)`` with
``d`` the part of ``lam_hat - M i_hat`` in phase with ``lam_hat``. In steady state
``lam - M i`` is in quadrature (``-j M i_q``, the slip), the direction a speed error also
drives the current error, so the two laws would fight; the in-phase part is non-zero only while
the flux changes, which the engine's flux-command injection (``[flux_injection]``) provides.
The projection is this project's decoupling choice. Both write the controller's model
(``MODEL_STATE``), which the observer itself and the IFOC slip use.

The R2 law reads R2 through the voltage equation, whose ``R1 i`` drop is much the larger term
at low stator frequency, so it needs R1_hat better than a drive can know it (measured
2026-11-30 on ``injection-robust``'s timeline with this law and a flux injection of 0.1). On
Table IV at zero stator frequency (75 rpm regenerating the rated torque) from R2_hat = R2:
R1_hat exact, R2_hat 0.3 % off at the end; 0.02 % low, R2_hat and the speed in a limit cycle
(+-2.5 %, 72-76 rpm); 0.02 % high, R2_hat swinging down to 0.85 R2 (the speed to 86 rpm); 0.2 %
and 1 % low, at its clamp. At 0.3 of the rated speed without load, R1_hat 0.03 % low left
R2_hat 3.3 % (Table IV), 1.5 % (Krause 50 hp) and 0.3 % (Aalto 2.2 kW) off. The standstill R1
test's own fit error is 0.01-0.03 % on the average inverter: with it the zero-frequency study
(84 runs) converged in 37 and lost 1, the machine envelope (336) converged in 287 and lost
none, against 72 and 320 with R1_hat exact. The EKF's R2 state, which takes R1's error as
process noise, ended within 1.6 % from R1_hat 2-6 % off in the same starts
(tests/drive/test_r1_standstill_any_estimator.py), but within 5 % in only 33 of the
zero-frequency study's 84 runs (none lost).

Discretisation: one RK4 step per control period with the voltage held (known exactly) and the
correction held; with exact parameters the true state is then a fixed point of the observer to
the plant integrator's accuracy, so no discretisation bias appears in the speed estimate.
"""

from __future__ import annotations

import numpy as np

from imdrive.kernels.estimators.common import to_frame
from imdrive.kernels.estimators.registry import ReducedState, register_kernel
from imdrive.kernels.jit import njit
from imdrive.kernels.model import model_inductances
from imdrive.kernels.records import c16, f8, i8, record_dtype

#: Parameters (defaults from :mod:`imdrive.design.estimators`).
AFO_PARAMS = record_dtype(
    [
        ("gain_mode", i8),  # 0: g1, g2 as given; 1: g2 = -rho (R1_hat + sigma L1 g1) L2/M;
        # 2: the same with rho scheduled by the operating point (scheduled_rho)
        ("rho", f8),  # share of the regeneration gain (gain_mode 1), 0..1
        ("g1", f8),  # current-equation gain, 1/s
        ("g2", f8),  # flux-equation gain, ohm (gain_mode 0)
        ("Kp", f8),  # speed adaptation, proportional, (rad/s)/(A Wb)
        ("Ki", f8),  # speed adaptation, integral, (rad/s^2)/(A Wb)
        ("a_w", f8),  # the bandwidth Kp, Ki give, rad/s: slowed at low stator frequency
        # (adaptation_share; 0: never)
        ("k_R1", f8),  # R1 adaptation gain, ohm/(A^2 s); 0: off
        ("k_R2", f8),  # R2 adaptation gain, ohm/(A Wb s); 0: off
        ("R_min", f8),  # lower clamp of the adapted resistances, fraction of the initial one
        ("R_max", f8),  # upper clamp, fraction of the initial one
    ]
)

#: State.
AFO_STATE = record_dtype(
    [
        ("i_hat_ab", c16),  # observed stator current, A
        ("lam_ab", c16),  # observed rotor flux, Wb
        ("int_e", f8),  # integral of eps, A Wb s
        ("w_r_hat", f8),  # speed estimate, electrical rad/s
        ("e_ab", c16),  # current error i - i_hat at the last sample, A
        ("eps", f8),  # last speed adaptation error, A Wb
        ("R1_0", f8),  # initial R1_hat and R2_hat (clamps), ohm; set on the first step
        ("R2_0", f8),
    ]
)


@njit(cache=True)
def _deriv(v, i, lam, w, R1, R2, M, L2, sigma_L1, corr_i, corr_l):
    k = M / L2
    a = complex(R2 / L2, -w)  # 1/T2 - j w
    R_sig = R1 + k * k * R2
    di = (v - R_sig * i + k * a * lam) / sigma_L1 + corr_i
    dl = (M * R2 / L2) * i - a * lam + corr_l
    return di, dl


#: The scheduled gain's margin (``gain_mode = 2``): the plain observer's unstable band is
#: shrunk until its edge lies at ``1/SCHEDULE_MARGIN`` of the stator frequency the observer runs
#: at. Measured on the realistic drive (docs/estimators.md's low-speed grid, 15 points): 2 and 4
#: lost control at 70 rpm regenerating the rated torque (-0.3 Hz), 8 held every point (13 within
#: 3 rpm), 16 and larger moved that point and 45 rpm regenerating 6 N m further off (+50 ... +89
#: and -2.7 ... -6.4 rpm); on the ideal drive's zero-frequency study 4 and 8 alike.
SCHEDULE_MARGIN = 8.0


@njit(cache=True)
def scheduled_rho(p, m, s, M, L2, sigma_L1):
    """The share ``rho`` the operating point needs (``gain_mode = 2``), capped at ``p.rho``.

    With ``g2 = -rho R' L2/M`` (``R' = R1_hat + sigma L1 g1``) the steady-state speed sensitivity
    keeps the sign of ``w_e`` where ``w_e^2 (A + rho R') + w_e w_s R' (1 - rho) > 0``, ``A =
    sigma L1/T2 + k^2 R2`` (the module docstring's ``Im D``); ``rho`` is the smallest value
    that holds this at ``w_e/SCHEDULE_MARGIN``, so 0 in motoring and without load, rising
    to ``p.rho`` as a regenerating drive nears zero stator frequency. ``w_s`` and ``w_e`` are
    the observer's own: the current model's slip ``(M/T2) Im(conj(lam) i)/|lam|^2`` and
    ``w_r_hat + w_s``. ``M, L2, sigma_L1``: the model's inductances this step (H).

    Why: ``rho`` near 1 makes the flux equation nearly the open voltage model, whose error
    mode the observer then barely damps; on the realistic drive the constant gain
    (``gain_mode = 1``) lost control at 70 rpm regenerating the rated torque and ended 4.5 rpm
    off at 45 rpm regenerating, which the scheduled gain holds within 3 rpm
    (docs/estimators.md). Tried and not kept: ``rho`` rising with the stator frequency as well
    (from 0.1 to 0.2 of the rated, whatever the load, for the voltage model's independence of
    R2_hat at speed): on the machine envelope it held Krause 3 and 50 hp at half speed from
    R2_hat(0) = 1.3 R2 (three runs that lose control without it) but moved four of the Aalto
    machine's half-speed runs from 1.2 and 1.3 R2 out of the converged column (325 of 336
    converged either way), and the observer with R1 adaptation lost control in 4 of the 10
    cases of the realistic drive's bench (none without it).
    """
    lam = s.lam_ab
    l2 = lam.real * lam.real + lam.imag * lam.imag
    if l2 <= 0.0:
        return p.rho
    i = s.i_hat_ab
    T2 = L2 / m.R2_hat
    w_s = (M / T2) * (lam.real * i.imag - lam.imag * i.real) / l2
    w_e = (s.w_r_hat + w_s) / SCHEDULE_MARGIN
    k = M / L2
    R_p = m.R1_hat + sigma_L1 * p.g1
    A = sigma_L1 / T2 + k * k * m.R2_hat
    den = R_p * (w_e * w_e - w_e * w_s)
    if den <= 0.0:  # w_e = 0, or motoring with w_e w_s >= w_e^2: no band
        return p.rho if w_e == 0.0 and w_s != 0.0 else 0.0
    r = -(w_e * w_e * A + w_e * w_s * R_p) / den
    return min(max(r, 0.0), p.rho)


@njit(cache=True)
def afo_gain(p, m, s, M, L2, sigma_L1):
    """``(g1, g2)`` in use: 1/s and ohm (see the module docstring); ``M, L2, sigma_L1`` the
    model's inductances this step, H."""
    if p.gain_mode == 0:
        return p.g1, p.g2
    rho = p.rho if p.gain_mode == 1 else scheduled_rho(p, m, s, M, L2, sigma_L1)
    return p.g1, -rho * (m.R1_hat + sigma_L1 * p.g1) * L2 / M


@njit(cache=True)
def afo_step(p, m, s, v_prev_alpha, v_prev_beta, i_alpha, i_beta, Ts, share=1.0):
    """Advance the observer over the period that just ended to this sample, and adapt.

    The state holds the observer at the previous sample and its current error there; the
    observer is integrated over the period that just ended (RK4, the voltage applied over it
    and that correction held) to a prediction for this sample, whose current error drives the
    adaptation laws and the next period's correction.

    Parameters
    ----------
    p : AFO_PARAMS record
    m : MODEL_STATE record
        Read (``R1_hat``, ``R2_hat``, inductances) and, with adaptation on, written.
    s : AFO_STATE record
        Updated in place; ``w_r_hat`` electrical rad/s.
    v_prev_alpha, v_prev_beta : float
        Voltage applied over the period that just ended, V.
    i_alpha, i_beta : float
        Stator current at this sample, A.
    Ts : float
        Control period, s.
    share : float
        The share of the speed adaptation's bandwidth in use, 0.5..1
        (:func:`adaptation_share`).
    """
    if s.R1_0 == 0.0:
        s.R1_0 = m.R1_hat
        s.R2_0 = m.R2_hat
    M, L1, L2, sigma_L1 = model_inductances(m)
    g1, g2 = afo_gain(p, m, s, M, L2, sigma_L1)
    v = complex(v_prev_alpha, v_prev_beta)
    i0 = s.i_hat_ab
    l0 = s.lam_ab
    w = s.w_r_hat
    R1 = m.R1_hat
    R2 = m.R2_hat
    ci = g1 * s.e_ab
    cl = g2 * s.e_ab
    k1i, k1l = _deriv(v, i0, l0, w, R1, R2, M, L2, sigma_L1, ci, cl)
    h = 0.5 * Ts
    k2i, k2l = _deriv(v, i0 + h * k1i, l0 + h * k1l, w, R1, R2, M, L2, sigma_L1, ci, cl)
    k3i, k3l = _deriv(v, i0 + h * k2i, l0 + h * k2l, w, R1, R2, M, L2, sigma_L1, ci, cl)
    k4i, k4l = _deriv(v, i0 + Ts * k3i, l0 + Ts * k3l, w, R1, R2, M, L2, sigma_L1, ci, cl)
    i1 = i0 + (Ts / 6.0) * (k1i + 2.0 * k2i + 2.0 * k3i + k4i)
    l1 = l0 + (Ts / 6.0) * (k1l + 2.0 * k2l + 2.0 * k3l + k4l)
    # the current error at this sample, and the adaptation laws
    e = complex(i_alpha, i_beta) - i1
    eps = e.real * l1.imag - e.imag * l1.real
    s.int_e += Ts * share * eps
    s.w_r_hat = share * p.Kp * eps + p.Ki * s.int_e
    s.eps = eps
    if p.k_R1 != 0.0:
        r = m.R1_hat - Ts * p.k_R1 * (e.real * i1.real + e.imag * i1.imag)
        m.R1_hat = min(max(r, p.R_min * s.R1_0), p.R_max * s.R1_0)
    if p.k_R2 != 0.0:
        # (lam_hat - M i_hat) projected on the flux direction: its quadrature part is the
        # slip's, which a speed error also excites; the in-phase part moves only with the flux
        # (the injection), so R2 and the speed are told apart
        d = l1 - M * i1
        l2 = l1.real * l1.real + l1.imag * l1.imag
        if l2 > 0.0:
            d = ((d.real * l1.real + d.imag * l1.imag) / l2) * l1
        r = m.R2_hat + Ts * p.k_R2 * (e.real * d.real + e.imag * d.imag)
        m.R2_hat = min(max(r, p.R_min * s.R2_0), p.R_max * s.R2_0)
    s.i_hat_ab = i1
    s.lam_ab = l1
    s.e_ab = e


#: The speed adaptation runs at its full bandwidth ``p.a_w`` where the sixth harmonic of the
#: stator frequency, ``6 |w_e|``, reaches it, and below at that share of it, never under
#: :data:`SHARE_MIN` (:func:`adaptation_share`).
HARMONIC = 6.0
SHARE_MIN = 0.5


@njit(cache=True)
def adaptation_share(p, w_e):
    """The share of the speed adaptation's bandwidth in use at the stator frequency ``w_e``
    (electrical rad/s): ``min(1, max(SHARE_MIN, 6 |w_e| / p.a_w))``, 1 if ``p.a_w`` is 0.

    A dead-time bridge distorts the current at six times the stator frequency; where the
    adaptation is as fast as that harmonic, its ripple and the current error's correlate and
    bias the estimate. Measured on Table IV's dead-time bridge at 0.1 of the rated speed
    without load (``envelope-full``'s grid, 80 Hz adaptation, 36 Hz harmonic): the estimate
    3.2-4.6 rpm off and R̂2 1.6-4.0 % (the thermal ramp the larger), against 1.0-1.7 rpm
    and 0.3-0.9 % at 40 Hz, which this share gives there
    (tests/drive/test_afo_bridge_low_speed.py). On the realistic drive at 70 rpm regenerating
    the rated torque (-0.09 Hz) the full bandwidth lost control where the half holds a state
    104 rpm off (docs/estimators.md). Above, the full bandwidth holds the drive from a high
    R̂2 at mid speed (config/estimators_afo.py, ``afo_bandwidth_Hz``). Table IV's whole
    rating on the observer (``envelope-full``, 1920 runs): within goal 480/476/478/456
    (ideal constant/ramp, bridge constant/ramp) with this share, 480/476/468/436 without."""
    if p.a_w <= 0.0:
        return 1.0
    return min(max(HARMONIC * abs(w_e) / p.a_w, SHARE_MIN), 1.0)


@njit(cache=True)
def afo_restart(m, s, i_ab):
    """Restart from the magnetised standstill (``EstimatorInput.restart``: the drive's
    standstill R1 test has just set R1_hat): the current's estimate the current ``i_ab``, the
    rotor flux's its steady state ``M_hat i_ab`` (at standstill ``p lam = 0`` gives ``lam =
    M i``), the speed and its integral zero. Integrated through the test with R1_hat(0), the
    flux estimate holds an error that the observer's gain, designed to keep regeneration
    stable (``rho`` near 1), barely damps at zero stator frequency: measured on Krause 500 hp
    from R1_hat(0) = 1.1 R1 at 10 rpm, the estimate ran 3 rpm off as the ramp began and the
    drive lost control when the rated regenerating load came (held with R1 exact from the
    start)."""
    s.i_hat_ab = i_ab
    s.lam_ab = m.M_hat * i_ab
    s.e_ab = 0j
    s.int_e = 0.0
    s.w_r_hat = 0.0


@njit(cache=True)
def afo_estimate(p, m, s, inp):
    """The full-order observer in the estimator contract; it has no flux error (``0j``)."""
    if inp.restart:
        afo_restart(m, s, inp.i_prev_ab)
    a = adaptation_share(p, inp.w_e)
    afo_step(p, m, s, inp.v_ab.real, inp.v_ab.imag, inp.i_ab.real, inp.i_ab.imag, inp.Ts, a)
    return s.w_r_hat, 0j


@njit(cache=True)
def afo_flux(s):
    """The observer's rotor-flux estimate, stationary frame, Wb."""
    return s.lam_ab


# --- the observer's states in the stability maps' reduced drive state (kernels/linearise.py) --

#: Names and typical magnitudes of the observer's states in the reduced state (controller's
#: frame): its current and rotor flux at the sample, the current error that drives the next
#: period's correction, the adaptation's integral and the speed estimate (the next period's
#: model runs at it). ``eps`` is not read again, ``R1_0``/``R2_0`` are constants.
REDUCED_NAMES = (
    "i_hat_d", "i_hat_q", "lam_d", "lam_q", "e_d", "e_q", "int_e", "w_r_hat",
)  # fmt: skip
REDUCED_SCALE = (0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 1e-4, 1.0)


@njit(cache=True)
def afo_reduce(p, s, c, z, k):
    """The observer's states into ``z[k:k + 8]`` (``ReducedState.reduce``)."""
    z[k], z[k + 1] = to_frame(c, s.i_hat_ab)
    z[k + 2], z[k + 3] = to_frame(c, s.lam_ab)
    z[k + 4], z[k + 5] = to_frame(c, s.e_ab)
    z[k + 6] = s.int_e
    z[k + 7] = s.w_r_hat


@njit(cache=True)
def afo_restore(z, k, s):
    """``z[k:k + 8]`` back into the observer's state (``ReducedState.restore``)."""
    s.i_hat_ab = complex(z[k], z[k + 1])
    s.lam_ab = complex(z[k + 2], z[k + 3])
    s.e_ab = complex(z[k + 4], z[k + 5])
    s.int_e = z[k + 6]
    s.w_r_hat = z[k + 7]


def afo_steady(c, p, I, w_e, w_r_hat):
    """The observer's states in the continuous steady state (``ReducedState.steady``): its
    current the stator current ``I`` (no error), its flux the rotor model's at the estimate,
    ``M_hat I / (1 + j (w_e - w_r_hat) T2_hat)``, and the adaptation's integral ``w_r_hat /
    Ki`` (``eps = 0``)."""
    n = len(I)
    z = np.zeros((n, len(REDUCED_NAMES)))
    lam = c["M_hat"] * I / (1.0 + 1j * (w_e - w_r_hat) * (c["L2_hat"] / c["R2_hat"]))
    z[:, 0], z[:, 1] = I.real, I.imag
    z[:, 2], z[:, 3] = lam.real, lam.imag
    z[:, 6] = w_r_hat / p["Ki"] if p["Ki"] != 0 else 0.0
    z[:, 7] = w_r_hat
    return z


KERNEL = register_kernel(
    "afo",
    AFO_PARAMS,
    AFO_STATE,
    afo_estimate,
    flux=afo_flux,
    reduced=ReducedState(
        REDUCED_NAMES, REDUCED_SCALE, afo_reduce, afo_restore, afo_steady, "w_r_hat"
    ),
)
