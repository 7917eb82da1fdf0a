"""The fuzzy-logic rotor-resistance compensator in the drive (paper §4, Fig. 1).

Every compensator period (``P_COMP_N`` control periods) after the enable time it forms

    E  = e_d0                      (the MRAS flux error in the rotor-flux frame, Wb)
    DE = E - E_previous            (change per compensator period, Wb)

scales them (``P_COMP_GE``, ``P_COMP_GDE``, 1/Wb: the paper's thresholds are in units of
1e-6, so a gain of 1e6 reproduces them), looks up the output level CR (-6 ... 6) in the 13 x 13
table (the paper's printed Table III or one compiled from rules, :mod:`imdrive.fuzzy`) and
updates

    R2_hat <- clip(R2_hat + G_CR * CR, R2_min, R2_max)

The MRAS and the slip calculation read ``R2_hat`` from the controller state, so both use the
new value from the next sample on.

Persistent-excitation variant (this project's, not the paper's): a sinusoid of amplitude
``P_INJ_AMP`` and frequency ``P_INJ_FREQ`` is added to the flux-current reference id*
(:func:`imdrive.control.foc_step`), and the compensator's input becomes the synchronous
detection ``2 e_d0 sin(phase)`` of e_d0 with the injected sinusoid. Averaged over whole
injection periods (the compensator period) it is the in-phase part of the e_d0 oscillation,
which the rotor-time-constant mismatch creates: with the flux responding as
``1/(1 + s T2)`` in the plant and ``1/(1 + s T2_hat)`` in the adjustable model, the in-phase
part of their difference has the sign of ``T2_hat - T2``, i.e. it is negative when
``R2_hat > R2`` — the same sign convention as the paper's e_d0, so the same table applies.
A constant (e.g. discretisation) bias of e_d0 averages out.

By default E is the mean of the input over the compensator period rather than a single sample
(``P_COMP_AVG``): a boxcar anti-aliasing filter that keeps ripple out of the quantiser.
"""

from __future__ import annotations

import math

from numba import njit

from imdrive.kernels.fuzzy import lookup
from imdrive.kernels.layout import (
    C_COMP_ACC,
    C_COMP_STARTED,
    C_CR,
    C_DEMOD,
    C_E_D0,
    C_E_D0_PREV,
    C_INJ_PHASE,
    C_R2_HAT,
    P_COMP_AVG,
    P_COMP_GCR,
    P_COMP_GDE,
    P_COMP_GE,
    P_COMP_INPUT,
    P_COMP_N,
    P_COMP_T_ON,
    P_INJ_FREQ,
    P_INJ_LPF,
    P_INJ_T_ON,
    P_R2_HAT_MAX,
    P_R2_HAT_MIN,
)


@njit(cache=True)
def injection_sine(par, c, t, Ts):
    """``sin(phase)`` of the injected sinusoid at this sample, 0 before ``P_INJ_T_ON``.

    Advances the phase held in ``c`` by one period. The injected flux current is
    ``P_INJ_AMP`` times this value, and :func:`demodulate` detects e_d0 with the same value.
    """
    if t < par[P_INJ_T_ON]:
        return 0.0
    ph = c[C_INJ_PHASE]
    nxt = ph + 2.0 * math.pi * par[P_INJ_FREQ] * Ts
    c[C_INJ_PHASE] = nxt - 2.0 * math.pi if nxt >= 2.0 * math.pi else nxt
    return math.sin(ph)


@njit(cache=True)
def demodulate(par, c, sine, Ts):
    """Synchronous detection of e_d0 with the injected sinusoid (updates ``C_DEMOD``).

    ``sine`` is :func:`injection_sine` of this sample. With ``P_INJ_LPF > 0`` the product
    ``2 e_d0 sine`` is also low-pass filtered (rad/s), for display.
    """
    prod = 2.0 * c[C_E_D0] * sine
    w_lp = par[P_INJ_LPF]
    if w_lp > 0.0:
        c[C_DEMOD] += (1.0 - math.exp(-w_lp * Ts)) * (prod - c[C_DEMOD])
    else:
        c[C_DEMOD] = prod


@njit(cache=True)
def compensator_input(par, c):
    """The signal the compensator feeds on: e_d0 (paper) or its demodulated version, Wb."""
    if par[P_COMP_INPUT] != 0.0:
        return c[C_DEMOD]
    return c[C_E_D0]


@njit(cache=True)
def compensator_update(par, c, table, E):
    """One compensator decision from the input ``E`` (Wb); updates ``C_R2_HAT`` in ``c``.

    Returns the output level CR.
    """
    if c[C_COMP_STARTED] == 0.0:
        c[C_COMP_STARTED] = 1.0
        c[C_E_D0_PREV] = E  # no change is known at the first sample
    DE = E - c[C_E_D0_PREV]
    c[C_E_D0_PREV] = E
    cr = lookup(table, par[P_COMP_GE] * E, par[P_COMP_GDE] * DE)
    r2 = c[C_R2_HAT] + par[P_COMP_GCR] * cr
    c[C_R2_HAT] = min(max(r2, par[P_R2_HAT_MIN]), par[P_R2_HAT_MAX])
    c[C_CR] = cr
    return cr


@njit(cache=True)
def compensator_step(par, c, table, t, k):
    """Called every control period ``k`` at time ``t`` after the MRAS update."""
    if t < par[P_COMP_T_ON]:
        return
    n = max(int(par[P_COMP_N]), 1)
    c[C_COMP_ACC] += compensator_input(par, c)
    if k % n != 0:
        return
    if par[P_COMP_AVG] != 0.0 and c[C_COMP_STARTED] != 0.0:
        E = c[C_COMP_ACC] / n
    else:
        E = compensator_input(par, c)
    c[C_COMP_ACC] = 0.0
    compensator_update(par, c, table, E)
