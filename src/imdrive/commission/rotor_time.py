"""The first test: the rotor time constant from the stator voltage's step response.

Every later test's durations and the AC test's frequencies are multiples of the rotor time
constant ``T2 = L2/R2`` this test measures: the rotor flux settles with it after any step of the
stator current at standstill, so it is what a level must outlast; the nameplate's slip (missing
from many plates) only sets its order (``w_slip T2`` is 1.4 on the 3 hp library machines, 4.7
on the 2250 hp one).

Method: at standstill, with the stator current held at a constant ``I`` along alpha from
``t = 0`` (current controllers; no torque), the rotor flux obeys ``T2 dpsi_r/dt = M I - psi_r``
and the commanded voltage is::

    v(t) = R1 I + e(I) + (M^2 / L2) (I / T2) exp(-t / T2)

(``e``: the inverter's loss, constant). ``T2`` is the time constant of the exponential fitted
to ``v`` (a constant plus one exponential, least squares on the voltage averaged over short
blocks). The step is held for :data:`SPAN_T2` times the fitted ``T2``: it starts at that many
times the per-unit guess's ``T2`` (:func:`~imdrive.commission.base.guess_model`, about 0.1 s
at 50-60 Hz) and is run again, longer, while the fitted ``T2`` is more than
1/:data:`SPAN_T2` of it (a truncated exponential's fit is not trusted).

The current is :data:`FLUX_PU` x rated flux over the guess's magnetising inductance, at most
:data:`CURRENT_MAX_PU` x rated current: low enough that the rotor stays in the unsaturated
part of the magnetising curve on machines whose magnetising current is well below the guess's
(large ones), where ``T2`` is longest; saturation shortens it. What limits the accuracy: only
the order matters (the durations that use it carry margin); the current controllers' rise
(excluded, :data:`SKIP_T2`) and the inverter's loss, constant at a constant current.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from imdrive.commission.base import (
    HELD_ROTOR,
    NO_SPEED_LOOP,
    CommissioningFailed,
    Nameplate,
    run_test,
    test_scenario,
    window,
)

#: The step's current: this fraction of rated flux over the guess's M, per unit.
FLUX_PU = 0.2
#: The largest step current, per unit of rated peak current.
CURRENT_MAX_PU = 0.5
#: The step is held for at least this many fitted time constants.
SPAN_T2 = 8.0
#: The start of the step left out of the fit (the current controllers' rise), in units of
#: the step's span.
SKIP_T2 = 0.01
#: Runs before the test gives up (each twice as long as the last, at least).
MAX_RUNS = 7
#: Blocks the voltage is averaged over before the fit (each averages the current
#: controllers' limit cycle and the sensors' noise).
BLOCKS = 400


@dataclass
class RotorTimeResult:
    """What the step-response test found.

    Attributes
    ----------
    T2_s : float
        Rotor time constant, s.
    I_A : float
        The step's current, A.
    t_s, v_V : numpy.ndarray
        The block-averaged time (from the step), s, and commanded alpha voltage, V, of the
        last run.
    v_fit_V : numpy.ndarray
        The fitted exponential at ``t_s``.
    duration_s : float
        Simulated duration of all runs, s.
    """

    T2_s: float
    I_A: float
    t_s: np.ndarray
    v_V: np.ndarray
    v_fit_V: np.ndarray
    duration_s: float


def rotor_time_test(sc, npl: Nameplate, model: dict) -> RotorTimeResult:
    """Measure the rotor time constant of scenario ``sc`` (module docstring).

    Parameters
    ----------
    sc : Scenario
    npl : Nameplate
    model : dict
        The controller's model (``[estimator]`` keys), the per-unit guess: its ``M_H`` sets the
        step's current, ``(M_H + Ll2_H)/R2_ohm`` the first run's span.
    """
    M = model["M_H"]
    I = min(FLUX_PU * npl.psi_rated_Wb / M, CURRENT_MAX_PU * npl.I_rated_A)
    span = SPAN_T2 * (M + model["Ll2_H"]) / model["R2_ohm"]
    total = 0.0
    for _ in range(MAX_RUNS):
        scen = test_scenario(
            sc,
            "rotor-time",
            span,
            control={**NO_SPEED_LOOP, "speed_feedback": "measured", "flux_ref_Wb": I * M},
            estimator=model,
            plant=HELD_ROTOR,
        )
        res = run_test(scen, "rotor-time")
        total += span
        t, v, _ = window(res, SKIP_T2 * span, span, npl.delay)
        tb, vb = _blocks(t, v.real)
        T2, fit = _fit_exponential(tb, vb)
        if T2 is not None and SPAN_T2 * T2 <= span:
            return RotorTimeResult(T2, I, tb, vb, fit, total)
        span = max(2.0 * span, 1.5 * SPAN_T2 * (T2 or 0.0))
    raise CommissioningFailed(
        "rotor-time",
        f"the voltage after a {I:.3g} A step did not settle to one exponential within "
        f"{span / 2.0:.3g} s (a rotor time constant above {span / (2.0 * SPAN_T2):.3g} s, or "
        "no rotor)",
    )


def _blocks(t: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``t`` and ``v`` averaged over :data:`BLOCKS` equal blocks."""
    n = len(t) // BLOCKS * BLOCKS
    return t[:n].reshape(BLOCKS, -1).mean(axis=1), v[:n].reshape(BLOCKS, -1).mean(axis=1)


def _fit_exponential(t: np.ndarray, v: np.ndarray):
    """``(T, fit)`` of ``v = c + A exp(-t/T)`` (least squares; for each ``T`` on a grid the
    linear ``c, A``, then refined by ``scipy.optimize.minimize_scalar``), or ``(None, None)``
    when the voltage does not fall (``A <= 0``) or ``T`` is at the grid's top end."""
    from scipy.optimize import minimize_scalar

    span = t[-1] - t[0]

    def solve(logT):
        X = np.column_stack((np.ones_like(t), np.exp(-(t - t[0]) / np.exp(logT))))
        coef, *_ = np.linalg.lstsq(X, v, rcond=None)
        return coef, X

    def cost(logT):
        coef, X = solve(logT)
        return float(np.sum((X @ coef - v) ** 2))

    grid = np.log(span) + np.linspace(np.log(1e-3), np.log(10.0), 60)
    k = int(np.argmin([cost(g) for g in grid]))
    if k in (0, len(grid) - 1):
        return None, None
    sol = minimize_scalar(cost, bounds=(grid[k - 1], grid[k + 1]), method="bounded")
    coef, X = solve(sol.x)
    if not coef[1] > 0.0:
        return None, None
    return float(np.exp(sol.x)), X @ coef
