"""Pieces the speed estimators share (the MRAS's adjustable model is :func:`current_model_step`).

The rotor current model in the stationary frame (Park et al., eq. 2)::

    p lam = (-1/T2 + j w_r) lam + (M/T2) i,        T2 = L2/R2

is linear in ``lam`` for a given speed, so it is advanced over one control period exactly, for
a current varying linearly between its two samples (first-order hold), with the complex
exponential of ``z = (-1/T2 + j w_r) Ts`` and the functions ``phi1 = (e^z - 1)/z``,
``phi2 = (e^z - 1 - z)/z^2``.
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def current_model_step(lam, w_r, R2, L2, M, i0, i1, Ts):
    """Rotor flux after one period of the current model, Wb (complex, stationary frame).

    Parameters
    ----------
    lam : complex
        Rotor flux at the start of the period, Wb.
    w_r : float
        Electrical rotor speed, held over the period, rad/s.
    R2, L2, M : float
        Rotor resistance (ohm), rotor and magnetising inductances (H) of the model.
    i0, i1 : complex
        Stator current at the start and at the end of the period, A.
    Ts : float
        Period, s.
    """
    zT = complex(-R2 / L2, w_r) * Ts
    ez = math.exp(zT.real) * complex(math.cos(zT.imag), math.sin(zT.imag))
    if abs(zT) > 1e-4:
        phi1 = (ez - 1.0) / zT
        phi2 = (ez - 1.0 - zT) / (zT * zT)
    else:  # series, avoids cancellation
        phi1 = 1.0 + zT / 2.0 + zT * zT / 6.0
        phi2 = 0.5 + zT / 6.0 + zT * zT / 24.0
    b = M * R2 / L2 * Ts
    return ez * lam + b * (phi1 * i0 + phi2 * (i1 - i0))
