"""The fuzzy-logic rotor-resistance compensator in the drive (paper §4, Fig. 1).

Every compensator period (``p.n`` control periods) after the enable time it forms

    E  = e_d0                      (the MRAS flux error in the rotor-flux frame, Wb)
    DE = E - E_previous            (change per compensator period, Wb)

scales them (``p.G_E``, ``p.G_DE``, 1/Wb: the paper's thresholds are in units of
1e-6, so a gain of 1e6 reproduces them), looks up the output level CR (-6 ... 6) in the 13 x 13
table (the paper's printed Table III or one compiled from rules, :mod:`imdrive.fuzzy`) and
updates

    R2_hat <- clip(R2_hat + G_CR * CR, R2_min, R2_max)

The slip calculation (which runs after the compensator in the same period) and the MRAS (from
the next sample on) read ``R2_hat`` from the controller's model (MODEL_STATE).

Persistent-excitation variant (this project's, not the paper's): a sinusoid of amplitude
``p.inj_amp`` and frequency ``p.inj_freq`` is added to the flux-current reference id*
(:func:`imdrive.control.foc_step`), and the compensator's input becomes the synchronous
detection ``2 e_d0 sin(phase)`` of e_d0 with the injected sinusoid. Averaged over whole
injection periods (the compensator period) it is the in-phase part of the e_d0 oscillation,
which the rotor-time-constant mismatch creates: with the flux responding as
``1/(1 + s T2)`` in the plant and ``1/(1 + s T2_hat)`` in the adjustable model, the in-phase
part of their difference has the sign of ``T2_hat - T2``, i.e. it is negative when
``R2_hat > R2`` — the same sign convention as the paper's e_d0, so the same table applies.
A constant (e.g. discretisation) bias of e_d0 averages out.

By default E is the mean of the input over the compensator period rather than a single sample
(``p.average``): a boxcar anti-aliasing filter that keeps ripple out of the quantiser.
"""

from __future__ import annotations

import math

from numba import njit

from imdrive.kernels.fuzzy import lookup
from imdrive.kernels.records import b1, f8, record_dtype

#: Parameters of the fuzzy R2 compensator and of the injected sinusoid.
COMPENSATOR_PARAMS = record_dtype(
    [
        ("enabled", b1),  # compensator present
        ("t_on", f8),  # time it is enabled, s
        ("n", f8),  # compensator period in control periods
        ("G_E", f8),  # scaling gain of E = e_d0, 1/Wb
        ("G_DE", f8),  # scaling gain of DE = change of E per compensator period, 1/Wb
        ("G_CR", f8),  # resistance change per output level, ohm
        ("R2_min", f8),  # clamp, ohm
        ("R2_max", f8),  # clamp, ohm
        ("demodulated", b1),  # input: e_d0 (paper) or demodulated e_d0 (injection)
        ("average", b1),  # input is the mean over the compensator period, else a sample
        ("inj_amp", f8),  # amplitude of the sinusoid added to id*, A (0: off)
        ("inj_freq", f8),  # its frequency, Hz
        ("inj_lpf", f8),  # optional low-pass on the demodulated product, rad/s (0: none)
        ("inj_t_on", f8),  # time the injection starts, s
    ]
)

#: State of the compensator.
COMPENSATOR_STATE = record_dtype(
    [
        ("E_prev", f8),  # input at the last compensator sample, Wb
        ("cr", f8),  # last output level
        ("started", b1),  # the first sample has been taken
        ("acc", f8),  # running sum of the input over the current period, Wb
        ("inj_phase", f8),  # phase of the injected sinusoid, rad
        ("demod", f8),  # demodulated (optionally low-pass-filtered) e_d0, Wb
    ]
)

#: Log fields of this block.
LOG_FIELDS = ("e_d0_demod",)  # Wb


@njit(cache=True)
def injection_sine(p, s, t, Ts):
    """``sin(phase)`` of the injected sinusoid at this sample, 0 before ``p.inj_t_on``.

    Advances the phase held in ``s`` by one period. The injected flux current is
    ``p.inj_amp`` times this value, and :func:`demodulate` detects e_d0 with the same value.
    """
    if t < p.inj_t_on:
        return 0.0
    ph = s.inj_phase
    nxt = ph + 2.0 * math.pi * p.inj_freq * Ts
    s.inj_phase = nxt - 2.0 * math.pi if nxt >= 2.0 * math.pi else nxt
    return math.sin(ph)


@njit(cache=True)
def demodulate(p, s, e_d0, sine, Ts):
    """Synchronous detection of e_d0 with the injected sinusoid (updates ``s.demod``).

    ``sine`` is :func:`injection_sine` of this sample. With ``p.inj_lpf > 0`` the product
    ``2 e_d0 sine`` is also low-pass filtered (rad/s), for display.
    """
    prod = 2.0 * e_d0 * sine
    w_lp = p.inj_lpf
    if w_lp > 0.0:
        s.demod += (1.0 - math.exp(-w_lp * Ts)) * (prod - s.demod)
    else:
        s.demod = prod


@njit(cache=True)
def compensator_input(p, s, e_d0):
    """The signal the compensator feeds on: e_d0 (paper) or its demodulated version, Wb."""
    if p.demodulated:
        return s.demod
    return e_d0


@njit(cache=True)
def compensator_update(p, s, m, table, E):
    """One compensator decision from the input ``E`` (Wb); updates ``m.R2_hat`` (MODEL_STATE).

    Returns the output level CR.
    """
    if not s.started:
        s.started = True
        s.E_prev = E  # no change is known at the first sample
    DE = E - s.E_prev
    s.E_prev = E
    cr = lookup(table, p.G_E * E, p.G_DE * DE)
    r2 = m.R2_hat + p.G_CR * cr
    m.R2_hat = min(max(r2, p.R2_min), p.R2_max)
    s.cr = cr
    return cr


@njit(cache=True)
def compensator_step(p, s, m, table, e_d0, t, k):
    """Called every control period ``k`` at time ``t`` after the MRAS update (``e_d0``, Wb)."""
    if t < p.t_on:
        return
    n = max(int(p.n), 1)
    s.acc += compensator_input(p, s, e_d0)
    if k % n != 0:
        return
    if p.average and s.started:
        E = s.acc / n
    else:
        E = compensator_input(p, s, e_d0)
    s.acc = 0.0
    compensator_update(p, s, m, table, E)


@njit(cache=True)
def log_compensator(row, s):
    """Write this block's :data:`LOG_FIELDS` into the log record ``row``."""
    row.e_d0_demod = s.demod
