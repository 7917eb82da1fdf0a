"""The in-phase response of the R2 detection to an R2 error, with the slip coupling and the
comparison filter: what the injection's frequency schedule weighs
(:func:`imdrive.kernels.gating.injection_by_response`) and what
:mod:`imdrive.studies.detection_gain` compares with measured runs.

In the controller's frame the current model's rotor-flux error ``e = e_d + j e_q`` answers a
relative R2 error ``r`` (``R2_hat = R2 (1 + r)``) as::

    (s + 1/T2) e_d =  w_sl e_q + F_d,     F_d = r dpsi_d/dt
    (s + 1/T2) e_q = -w_sl e_d + F_q,     F_q = -r w_sl psi~_d

``psi~_d``: the rotor flux's answer to the injected flux current ``a sin(w_i t)``,
``M a / (1 + j w_i T2)``; ``w_sl``: the slip. ``F_q`` is there when the current model runs at
a speed that carries the slip error of the same R2 error, ``-r w_sl`` (a speed estimator that
holds its own model consistent, as the adaptive observer does in steady state), and the
detection neither corrects that speed nor decouples the slip: the detector's speed correction
is off while regenerating below the rated slip frequency
(:mod:`imdrive.kernels.flux_detector`), its slip decoupling off below 0.3 of the rated
frequency. Then, per unit of ``M a r`` and with ``x = w_i T2``, ``sg = w_sl T2``::

    h1 = ((1 + jx) jx - sg^2) / ((1 + jx) ((1 + jx)^2 + sg^2))

and with the speed corrected (``e_q`` held at zero at the injection frequency) or no slip::

    h0 = jx / (1 + jx)^2,      Re h0 = S = 2 x^2 / (1 + x^2)^2

the sensitivity the law divides by (:func:`imdrive.kernels.sensitivity.in_phase_sensitivity`).
``Re h1`` changes sign where ``x`` is small against ``|sg|``: regenerating the rated torque on
Table IV (``sg = -1.45``) it is ``-0.26`` at 1.1 Hz against ``S = +0.40``, and ``+0.35`` at
2 Hz; the law reading such a window walks R2_hat away from R2.

Both flux models pass the comparison filter ``1/(s + wc)`` in the stationary frame, where the
injection's d-axis signal lies in two side bands ``w_e +- w_i``; back in the controller's frame
the in-phase response is multiplied by ``G = (H(w_e + w_i) + conj H(w_e - w_i)) / 2``,
``H(w) = jw / (jw + wc)``.
"""

from __future__ import annotations

from imdrive.kernels.jit import njit


@njit(cache=True)
def responses(w_i, T2, w_sl, w_e, wc):
    """``(Re[G h0], Re[G h1])``: the decoupled and the slip-coupled in-phase response to a
    relative R2 error, per unit of ``M a`` (module docstring; arguments as
    :func:`in_phase_response`)."""
    z = complex(1.0, w_i * T2)
    jx = complex(0.0, w_i * T2)
    h0 = jx / (z * z)
    sg2 = (w_sl * T2) ** 2
    h1 = (z * jx - sg2) / (z * (z * z + sg2))
    G = complex(1.0, 0.0)
    if wc > 0.0:
        wp = w_e + w_i
        wm = w_e - w_i
        G = 0.5 * (
            complex(0.0, wp) / complex(wc, wp) + (complex(0.0, wm) / complex(wc, wm)).conjugate()
        )
    return (G * h0).real, (G * h1).real


@njit(cache=True)
def in_phase_response(w_i, T2, w_sl, w_e, wc, coupled):
    """The detection's in-phase response to a relative R2 error, per unit of ``M a``
    (dimensionless; module docstring): ``Re[G h0]``, or with ``coupled`` the smaller of
    ``Re[G h0]`` and ``Re[G h1]`` (the speed path's state is not known within a window).

    Parameters
    ----------
    w_i : float
        The injection's angular frequency, rad/s.
    T2 : float
        The rotor time constant, s.
    w_sl : float
        The slip, electrical rad/s (negative regenerating).
    w_e : float
        The stator frequency, electrical rad/s (signed).
    wc : float
        The comparison filter's corner, rad/s (0: no filter, ``G = 1``).
    coupled : bool
        Weigh the slip-coupled response ``h1`` too.
    """
    r0, r1 = responses(w_i, T2, w_sl, w_e, wc)
    return min(r0, r1) if coupled else r0
