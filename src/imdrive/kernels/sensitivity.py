"""The injection's in-phase sensitivity to an R2 error, and the ratio that keeps the fuzzy R2
compensator's thresholds the same on a saturated machine.

The rotor flux answers an injected flux current ``i sin(w_i t)`` through ``M/(1 + s T2)``; the
synchronous detection sees the part in phase with the current, whose change per relative R2
error is :func:`in_phase_sensitivity`. Used by
:func:`imdrive.kernels.compensator.compensator_update` and the Kalman law
(:mod:`imdrive.kernels.r2_kalman`).
"""

from __future__ import annotations

import math

from imdrive.kernels.gating import injection_frequency_Hz
from imdrive.kernels.jit import njit
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
    w_i = 2.0 * math.pi * injection_frequency_Hz(p, s)
    s_sec = M * in_phase_sensitivity(w_i, (m.Ll2_hat + M) / m.R2_hat)
    s_inc = m.L_inc_hat * in_phase_sensitivity(w_i, incremental_L2(m) / m.R2_hat)
    return s_sec / max(s_inc, 1e-6 * s_sec)
