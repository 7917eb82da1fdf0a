"""An R2 law written outside the package, as a user would (the R2-law plug-in example).

Relaxation on the measured error: each accepted decision window measures the relative error
``r = R2_hat/R2 - 1`` (the detected flux error over its analytic sensitivity, handed to the
law as ``w.r``), so ``R2_hat / (1 + r)`` is a measurement of R2; the law moves R2_hat a share
``gain`` of the way there::

    R2_hat <- R2_hat / (1 + gain r)

With the detection's gain within 0.6-1.9 of the analytic sensitivity (measured,
kernels/r2_kalman.py) a gain of 0.5 contracts the error by 0.05-0.7 per window: it converges
geometrically, without the Kalman law's drift state (a ramp of R2 is followed with a lag).
It counts its decisions and its held windows, to show a law's own state.
"""

from __future__ import annotations

from typing import Annotated

from numba import njit

from imdrive.run.r2_laws import Float, LawRecords, f8, r2_law, record_dtype, register_law, setting

RELAX_PARAMS = record_dtype([("gain", f8)])
RELAX_STATE = record_dtype(
    [
        ("decisions", f8),  # windows that measured R2
        ("held", f8),  # windows the gating rejected
        ("r_last", f8),  # the last relative error measured
        ("R2_meas", f8),  # the R2 it measured, ohm
    ]
)


@njit(cache=True)
def relax_decide(p, s, m, w):
    """One accepted window: a share ``gain`` of the way to the measured R2 (ohm)."""
    s.decisions += 1.0
    r = max(w.r, -0.9)
    s.r_last = r
    s.R2_meas = m.R2_hat / (1.0 + r)
    return m.R2_hat / (1.0 + p.gain * r)


@njit(cache=True)
def relax_hold(p, s, m, w):
    """A rejected window: R2_hat left where it is."""
    s.held += 1.0


@njit(cache=True)
def relax_log(row, s):
    """Its own log field: the R2 the last window measured."""
    row.relax_R2_meas = s.R2_meas


KERNEL = register_law(
    "relax",
    RELAX_PARAMS,
    RELAX_STATE,
    relax_decide,
    relax_hold,
    log_fields=("relax_R2_meas",),
    log=relax_log,
)


@r2_law(
    "relax",
    None,
    "relaxation on the measured relative error",
    log_units={"relax_R2_meas": ("ohm", 1.0)},
)
class RelaxSettings:
    """Relaxation R2 law (``[plugins.settings.relax]``)."""

    gain: Annotated[
        Float, setting("share of the measured error corrected per window", gt=0.0, le=1.0)
    ] = 0.5

    def records(self, ctx):
        """Its gain; nothing from the machine."""
        return LawRecords(params={"gain": self.gain})
