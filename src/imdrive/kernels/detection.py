"""The detection's helpers: removing the flux error's mean in the stationary frame, and the
slip's coupling of the q-axis flux error into the d-axis one.

Used by :func:`imdrive.kernels.r2_tracking.track` and
:func:`imdrive.kernels.compensator.demodulate` (and importable from there).
"""

from __future__ import annotations

from imdrive.kernels.jit import njit

#: Corner of :func:`stationary_mean_removed`'s mean, per unit of the distance of the
#: injection's nearer side band from DC: the side bands keep their phase to
#: ``atan(0.02) = 1.1`` degrees and their gain to 0.02 %.
MEAN_CORNER_PER_SIDE_BAND = 0.02

#: The corner's bound, per unit of the detection filter's corner ``wc``: the error's constant
#: is the filter's settled output, which the mean must follow more slowly than the filter
#: settles.
MEAN_CORNER_PER_FILTER = 0.1


@njit(cache=True)
def stationary_mean_removed(s, e_ab, w_e, w_i, wc, Ts):
    """The flux error ``e_ab`` (stationary frame, Wb) less its mean there (updates
    ``s.dc_ab``).

    A constant error of the measured current -- the current sensors' offsets, 20 mA on the
    realistic presets -- enters both flux models as a constant, so the two models' difference
    carries a constant in the stationary frame: in the controller's frame a phasor turning at
    the stator frequency, which the synchronous detection at the injection's frequency ``w_i``
    rejects only as well as its one-period window does. The injection's R2 signal lies at the
    side bands ``w_e +- w_i`` of the stationary frame, which the frequency schedule keeps away
    from DC (:mod:`imdrive.kernels.gating`). So the mean is removed in the stationary frame by a
    first-order low-pass estimate whose corner is :data:`MEAN_CORNER_PER_SIDE_BAND` times the
    nearer side band's distance from DC, ``||w_e| - w_i|``, and at most
    :data:`MEAN_CORNER_PER_FILTER` times the filter's ``wc`` (1.5 rad/s behind the 15 rad/s
    filter, from about 0.3 of the rated speed up): the high-pass it leaves turns the side bands
    by at most 1.1 degrees, the slip decoupling's q-to-d correction included.

    Measured (2026-11-30) on ``injection-robust`` on the realistic drive (switching bridge,
    sensor offsets, noise, 12-bit ADC; 3 machines x 24 cells x 4 noise seeds,
    :mod:`imdrive.studies.realistic_envelope`): R2_hat within 2 % in 71, 72, 71, 71 of 72
    against 64, 66, 70, 69 without it; with the sensors' offsets taken out of the detection's
    current by an oracle instead, 71, 72, 69, 72. The same drive on the MRAS: 63, 60, 56, 71
    against 58, 54, 56, 66; it is not applied there yet (only to the error the detection forms
    itself, :mod:`imdrive.kernels.flux_detector`): on the encoder drive with a saturating
    machine (``tests/drive/test_encoder_saturation.py``) R2_hat swings between 0.9 and 1.2 R2
    with a period of about 10 s at half the rated speed regenerating from 0.81 R2, and with
    the removal the run ends at another phase of that swing (-11.3 % against -6.7 %; from
    0.8 R2 -2.25 against -1.37 %). The ideal drive near zero stator frequency, where the side bands
    can sit under the detection filter's corner, sets the corner: at 0.1 of the side band's
    distance (5.7 degrees) the zero-frequency study converged in 67 of 84 runs, at 0.05 in
    69, at 0.02 in 71, as without the removal (72 -> 73 within 5 %); the machine envelope 332
    of 336 either way. What it costs: on ``envelope-full``'s bridge, with no offsets to remove,
    480 / 451 of 480 within goal (480 / 456 with the dead-time compensation moved by 1e-9 of
    itself) against 480 / 460 (480 / 459): the ramp's misses at twice the rated speed, speed
    errors of 2-6 rpm with R2_hat within 1.7 %, went from 5-6 to 10-12; not yet explained.

    Parameters
    ----------
    s : COMPENSATOR_STATE record
    e_ab : complex
        The flux error in the stationary frame, Wb.
    w_e, w_i : float
        The controller's stator frequency and the injection's, rad/s.
    wc : float
        The corner of the filter behind the flux error, rad/s (its mean's corner is at most
        :data:`MEAN_CORNER_PER_FILTER` times it).
    Ts : float
        The control period, s.
    """
    # forward Euler: w_h Ts is at most 0.02 (w_e + w_i) Ts, a few thousandths
    w_h = min(MEAN_CORNER_PER_SIDE_BAND * abs(abs(w_e) - w_i), MEAN_CORNER_PER_FILTER * wc)
    s.dc_ab += w_h * Ts * (e_ab - s.dc_ab)
    return e_ab - s.dc_ab


#: Largest correction ``wc/|w|`` of the comparison filter ``s/(s + wc)`` (``|H| >= 0.32``)
#: :func:`slip_coupling` undoes: nearer DC the signal is lost, not recoverable.
MAX_HP_CORRECTION = 3.0


@njit(cache=True)
def slip_coupling(s, e_dq0, w_e, wc, w_s, T2_hat, Ts):
    """The part of the d-axis flux error that the slip couples in from the q-axis error, Wb
    (integrated in ``s.cpl_d``).

    In the controller's frame the rotor flux obeys
    ``dpsi_d/dt = (M i_d - psi_d)/T2 + (w_e - w_r) psi_q``, and the adjustable model is held on
    the d axis (``psi_hat_q = 0``); so a q-axis flux error drives the d-axis error through

        G(s) = w_s T2 / (1 + s T2),     w_s = w_e - w_r (the slip).

    The MRAS's speed loop holds ``e_q0`` near 0 but not at 0 through the injection's torque
    ripple (its bandwidth is finite), and at a large slip (``w_s T2 = i_q/i_d``: 3-5 at full
    load above base speed) that part is as large as the R2 signal and has the sign of
    ``w_s``: R2_hat ended 2 % low at 1.5 x base speed and drifted 28 % low at 2 x base speed,
    motoring, from R2_hat(0) = R2. ``w_s`` is the controller's slip command low-passed over
    ``T2_hat`` (``s.cpl_ws``): the raw command carries the speed loop's response to the
    estimate's PWM ripple, which on the dead-time bridge correlates with ``e_q0``'s and biased
    R2_hat 4-6 % low at no load. ``G`` is integrated in the time domain (forward Euler), not
    as a phasor at the injection frequency, because there the speed loop's own oscillation
    puts most of ``e_q0`` at other frequencies.

    ``e_q0`` is the error after the MRAS's comparison filter ``s/(s + wc)`` in the stationary
    frame, which near ``w_e ~ wc`` leaks a share ``wc/w_e`` of the d error (the R2 signal
    itself) into q; it is undone at the stator frequency, ``q = e_q0 - (wc/w_e) e_d0`` (the
    ratio bounded by :data:`MAX_HP_CORRECTION`; wc = 0: no filter).
    """
    q = e_dq0.imag
    if wc > 0.0:
        c = wc / max(abs(w_e), wc / MAX_HP_CORRECTION)
        q -= (c if w_e >= 0.0 else -c) * e_dq0.real
    # the slip command low-passed over T2: on a switching bridge its sample-to-sample ripple
    # (the speed loop's response to the estimate's PWM ripple) correlates with e_q0's
    s.cpl_ws += Ts / T2_hat * (w_s - s.cpl_ws)
    s.cpl_d += Ts * (s.cpl_ws * q - s.cpl_d / T2_hat)
    return s.cpl_d
