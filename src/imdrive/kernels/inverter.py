"""Voltage-source inverter.

The inverter turns the controller's voltage reference (held over one control period) into the
voltage the machine sees during that period, as a sequence of *segments* ``(duration, v_ab)``.
The average-value model returns one segment: the reference limited to the linear range of
space-vector modulation, ``|v| <= Vdc/sqrt(3)``, direction kept. A switching model (SVPWM with
dead time) returns up to seven segments per period from the same arguments, so the engine and
every controller stay unchanged when one is added.
"""

from __future__ import annotations

import math

from numba import njit

from imdrive.kernels.records import f8, i8, record_dtype

INV_AVERAGE = 0
MAX_SEGMENTS = 8
INVERTER_CODES = {"average": INV_AVERAGE}

#: Parameters of the inverter.
INVERTER_PARAMS = record_dtype(
    [
        ("Vdc", f8),  # DC-link voltage, V
        ("model", i8),  # INV_AVERAGE (switching models next)
    ]
)

#: Log fields this block's caller writes: the period-average voltage applied, V.
LOG_FIELDS = ("v_alpha", "v_beta")


@njit(cache=True)
def limit_magnitude(v_a, v_b, v_max):
    """Scale ``(v_a, v_b)`` down to magnitude ``v_max`` if longer; direction is kept."""
    mag = math.sqrt(v_a * v_a + v_b * v_b)
    if mag > v_max:
        k = v_max / mag
        return v_a * k, v_b * k
    return v_a, v_b


@njit(cache=True)
def inverter_segments(p, v_ref_a, v_ref_b, i_a, i_b, Ts, seg_dt, seg_va, seg_vb):
    """Voltage segments the machine sees over one control period.

    Parameters
    ----------
    p : INVERTER_PARAMS record
    v_ref_a, v_ref_b : float
        Voltage reference from the controller, stationary frame, V.
    i_a, i_b : float
        Stator current at the start of the period, A (used by dead-time models).
    Ts : float
        Control period, s.
    seg_dt, seg_va, seg_vb : float64[MAX_SEGMENTS]
        Outputs: duration (s) and voltage (V) of each segment.

    Returns
    -------
    int
        Number of segments written.
    """
    v_max = p.Vdc / math.sqrt(3.0)
    # only the average model exists so far; p.model selects future models
    va, vb = limit_magnitude(v_ref_a, v_ref_b, v_max)
    seg_dt[0] = Ts
    seg_va[0] = va
    seg_vb[0] = vb
    return 1
