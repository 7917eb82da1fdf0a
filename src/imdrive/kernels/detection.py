"""The detection's helper: removing the slip's coupling of the q-axis flux error into the d-axis
one.

Used by :func:`imdrive.kernels.compensator.demodulate` (and importable from there).
"""

from __future__ import annotations

from numba import njit

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
