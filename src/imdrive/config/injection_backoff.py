"""The injection's back-off band near the voltage limit (:func:`backoff_band`): where the
amplitude of ``[injection]``'s sinusoid starts to fall and where it reaches zero, with the
field weakening on (:func:`imdrive.kernels.compensator_range.injection_headroom`). It replaced
``injection.headroom_from`` and ``headroom_to`` in round 8 (issue 38; their deprecation note in
:mod:`imdrive.config.compensator_deprecated` has the measurement).
"""

from __future__ import annotations

#: The injection's back-off band (:func:`backoff_band`) with the estimation headroom: from this
#: much above ``injection.headroom_voltage`` to this much above it, fractions of ``Vdc/√3``.
BACKOFF_ABOVE_HEADROOM = (0.04, 0.10)
#: Without it: this much either side of the field weakening's voltage use.
BACKOFF_AROUND_FIELD_WEAKENING = 0.05


def backoff_band(headroom_voltage: float | None, field_weakening_voltage: float):
    """The voltage use (peak over an injection period, fraction of ``Vdc/√3``) from which the
    injection's amplitude backs off and where it reaches zero (``injection.headroom_from``,
    ``headroom_to``: deprecated), with the field weakening on (the compensator freezes
    below half amplitude).

    * With the estimation headroom the field weakening holds the period's peak at
      ``headroom_voltage``: the band sits above it, from 0.04 to 0.10 over it (0.92-0.98 at
      0.88), so the injection keeps its full amplitude in steady state and backs off only
      where a transient takes the voltage past the loop's hold.
    * Without it the field weakening holds the voltage use at ``field_weakening_voltage`` and
      the injection is off in field weakening: the band is centred there, ±0.05 (0.85-0.95 at
      0.9), so the amplitude is half, and the compensator freezes, where the field weakening
      takes over.

    Every preset, sweep, study and test paired the keys so; rounded to 1e-9, so the sums are
    the decimal numbers they had (0.9 + 0.05 is 0.9500000000000001 in floating point).
    """
    if headroom_voltage is not None:
        lo, hi = (headroom_voltage + d for d in BACKOFF_ABOVE_HEADROOM)
    else:
        d = BACKOFF_AROUND_FIELD_WEAKENING
        lo, hi = field_weakening_voltage - d, field_weakening_voltage + d
    return round(lo, 9), round(hi, 9)
