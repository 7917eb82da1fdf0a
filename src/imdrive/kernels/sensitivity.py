"""The injection's in-phase sensitivity to an R2 error, and the ratios that keep the R2
compensator's loop gain the same at every injection frequency and on a saturated machine.

The rotor flux answers an injected flux current ``i sin(w_i t)`` through ``M/(1 + s T2)``; the
synchronous detection sees the part in phase with the current, whose change per relative R2
error is :func:`in_phase_sensitivity`. Used by
:func:`imdrive.kernels.compensator.compensator_update`.
"""

from __future__ import annotations

import math

from numba import njit

from imdrive.kernels.model import incremental_L2


@njit(cache=True)
def in_phase_sensitivity(w_i, T2):
    """In-phase flux response to a relative R2 error, per unit of ``M i_inj`` (dimensionless).

    The rotor flux answers an injected flux current ``i sin(w_i t)`` as ``M/(1 + s T2)``; its
    part in phase with the current is ``M i / (1 + (w_i T2)^2)``. For ``R2_hat = R2 (1 + r)``
    (``T2_hat = T2 / (1 + r)``) the model's in-phase part differs from the plant's by
    ``-M i r S`` to first order, with::

        S = 2 (w_i T2)^2 / (1 + (w_i T2)^2)^2

    (0.50 at 2 Hz, 0.29 at 4 Hz, 0.16 at 6 Hz for T2 = 87 ms): the detected signal per % of
    R2 error falls with the injection frequency.
    """
    a = (w_i * T2) ** 2
    return 2.0 * a / (1.0 + a) ** 2


@njit(cache=True)
def injection_sensitivity_ratio(p, s, m):
    """``S(f_base) / S(f_in_use)`` (:func:`in_phase_sensitivity`) with the controller's T2_hat:
    the adaptive law scales its input by it, so its loop gain does not drop when the schedule
    moves to a higher frequency (measured at 150 rpm, -12 N m on 4 Hz: R2_hat 4 % off after
    10 s, still converging). The injected flux variation is small: on a saturation-aware
    model its time constant is the incremental one, ``(Ll2 + L_inc)/R2_hat``."""
    T2 = incremental_L2(m) / m.R2_hat
    f = s.inj_f if s.inj_f > 0.0 else p.inj_freq
    s_now = in_phase_sensitivity(2.0 * math.pi * f, T2)
    s_base = in_phase_sensitivity(2.0 * math.pi * p.inj_freq, T2)
    return s_base / max(s_now, 1e-6 * s_base)


@njit(cache=True)
def saturation_sensitivity_ratio(p, s, m):
    """``M S(T2) / (L_inc S(T2_inc))`` on a saturation-aware model (``m.sat_n > 0``), else 1.

    The injected flux variation is small, so the plant answers it with the incremental
    inductance ``L_inc`` and the incremental time constant ``T2_inc = (Ll2 + L_inc)/R2_hat``;
    the in-phase signal per % of R2 error is ``L_inc i S(w_i T2_inc)`` instead of the constant
    model's ``M i S(w_i T2)`` (:func:`in_phase_sensitivity`). The demodulated input is scaled
    by the ratio so that the table's thresholds and the gains mean the same error as on an
    unsaturated machine (0.41 at rated flux, 2 Hz on Table IV's machine with the default
    curve: the dead zone would otherwise be 2.4 times wider in R2 error).
    """
    if m.sat_n == 0:
        return 1.0
    M = m.M_hat
    w_i = 2.0 * math.pi * (s.inj_f if s.inj_f > 0.0 else p.inj_freq)
    s_sec = M * in_phase_sensitivity(w_i, (m.Ll2_hat + M) / m.R2_hat)
    s_inc = m.L_inc_hat * in_phase_sensitivity(w_i, incremental_L2(m) / m.R2_hat)
    return s_sec / max(s_inc, 1e-6 * s_sec)


@njit(cache=True)
def fine_loop_gain_ratio(p, m):
    """The adaptive law's fine-band gain over its value at the R2_hat it was tuned at.

    The fine step is a share of R2 per unit of the detected error (``G_CR`` is resolved as a
    share of ``R2_hat(0)``, ``p.R2_tuned``), and the detected error per % of R2 is
    :func:`in_phase_sensitivity` at the injection frequency and the rotor's time constant. As
    R2_hat moves away from where the gains were resolved both change: from ``R2_hat(0) = 0.7
    R2`` heated to ``1.2 R2`` (Table IV) the step is ``0.7 / 1.2`` of R2_hat's share and the
    1.17 Hz injection sits at 0.54 of the rotor's corner instead of 0.92 (``S`` 0.35 instead of
    0.50), so the loop gain per decision fell to 0.4 of its tuned value (and at a ramp's end
    R2_hat ran on by 0.9 % of R2, the drift unwound that slowly). This ratio puts it back:

        (R2_hat / R2_tuned) S(w_1, T2_tuned) / S(w_1, T2_hat)

    at the first injection frequency ``w_1`` (:func:`injection_sensitivity_ratio` scales the
    frequency in use to it), bounded to ``[1/4, 4]``.

    Parameters
    ----------
    p : COMPENSATOR_PARAMS record
        ``R2_tuned`` (ohm; 0: no ratio) and ``inj_freq`` (Hz).
    m : MODEL_STATE record
        The controller's model: ``R2_hat`` (ohm) and the rotor inductance.

    Returns
    -------
    float
        The ratio (dimensionless), 1 without ``p.R2_tuned``.
    """
    if p.R2_tuned <= 0.0:
        return 1.0
    L2 = incremental_L2(m)
    w_i = 2.0 * math.pi * p.inj_freq
    s_now = in_phase_sensitivity(w_i, L2 / m.R2_hat)
    s_tuned = in_phase_sensitivity(w_i, L2 / p.R2_tuned)
    g = (m.R2_hat / p.R2_tuned) * s_tuned / max(s_now, 1e-6 * s_tuned)
    return min(max(g, 0.25), 4.0)
