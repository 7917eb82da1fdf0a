"""Standstill DC test: the stator resistance and the inverter's voltage error.

Method (Schierling, "Self-commissioning -- a novel feature of modern inverter-fed induction
motor drives", IEE Conf. Power Electronics and Variable-Speed Drives, 1988; the DC test of
IEC 60034-28:2012 done by the drive's own inverter; the inverter model of Holtz and Quan,
"Sensorless vector control of induction motors at very low speed using a nonlinear inverter
model and parameter identification", IEEE Trans. Ind. Appl. 38(4), 2002): the current
controllers impose a DC current ``I`` along the alpha axis (phase a carries ``I``, phases b
and c ``-I/2``; no torque, the rotor stays still) at a ladder of levels, and the drive
records its commanded alpha voltage once the rotor flux has settled. In steady state::

    V(I) = R1 I + e(I),     e(I) = (2/3) (u(I) + u(I/2))

where ``u(i)`` is the voltage one phase loses at phase current ``i`` (dead time and device
drops; odd in ``i``). Beyond the current where the dead-time error has reached its plateau in
every phase, ``e`` is constant: the slope of ``V(I)`` over the upper levels (at least
:data:`PLATEAU_PU` of rated current) is ``R1``, its intercept ``e_inf = (4/3) u_inf``
(Rasmussen, Vadstrup, Borsting: the slope/intercept separation of the resistance from the
inverter's threshold voltage). Below, ``u`` is unfolded level by level on the ladder of
halving currents, ``u(I_k) = 1.5 (V_k - R1 I_k) - u(I_k/2)``.

Duration: :data:`LEVELS_PU` (11 levels) of :data:`DWELL_T2` = 10 rotor time constants each
(``T2`` measured by :mod:`~imdrive.commission.rotor_time`: 0.97 s on the Table IV machine,
11 s in all; 17.7 s per level on the 2250 hp one); currents 1 % to 100 % of rated peak
current. Ten time constants: a level's flux transient, about ``R2 dI`` in volts at its start,
is then below 1e-3 of the level's voltage over the averaging window (the settling check,
:data:`SETTLED_TOL`).

The same levels give the current sensors' relative gain ``g_b/g_a``. The controller holds
its *measured* current on the alpha axis (``m_a = I``, ``m_b = -I/2``), so with
``m_x = g_x i_x`` the true current has a beta part ``(I/sqrt 3)(1/g_a - 1/g_b)``, and the
beta voltage's slope over the plateau levels, per alpha voltage slope ``R1/g_a``, is
``r = (1 - g_a/g_b)/sqrt 3``: ``g_b/g_a = 1/(1 - sqrt(3) r)``. The inverter's loss has no
beta part on the plateau (phases b and c carry equal, saturated losses), and the offsets
move only the intercepts. A relative gain error makes a negative-sequence current error,
which the dead-time compensation and the observers then misplace
(``controller_model.current_gain_b_per_a``).

What limits the accuracy: the rotor-flux transient after each step (its voltage
``(M/L2) dpsi_r/dt`` decays with the rotor time constant; the level is averaged over its last
40 % and refused if its two halves differ, :data:`SETTLED_TOL`); the current sensors' gain
error enters ``R1`` directly (0.25 % in the realistic preset) and their offsets the table at
the smallest currents; below about 2 % of rated current the phase currents are within the
sensors' offset and noise, so the table's first nodes are uncertain; a resistive part of the
inverter's loss (an on-state slope resistance) is not separable from ``R1`` by this test.
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

#: The DC levels, per unit of rated peak current: a ladder of halving currents (so each
#: level's half is a level: the table unfolds exactly) and the upper levels for the slope.
LEVELS_PU = (0.01, 0.02, 0.04, 0.08, 0.16, 0.32, 0.4, 0.5, 0.64, 0.8, 1.0)
#: Levels from which the inverter's loss is on its plateau in every phase (half the current
#: in phases b and c), per unit of rated current: the R1 slope is fitted over them.
PLATEAU_PU = 0.3
#: Time at each level, in rotor time constants (measured).
DWELL_T2 = 10.0
#: Fraction of each level averaged (its end).
AVERAGE_FRACTION = 0.4
#: Largest difference between a level's two averaged halves, in volts per volt of the level's
#: mean (at least 5 % of rated phase voltage): a larger one has not settled.
SETTLED_TOL = 2e-3
#: The same below the plateau's levels (a limit cycle around the dead time's step).
SETTLED_TOL_LOW = 0.1


@dataclass
class DcResult:
    """What the DC test found.

    Attributes
    ----------
    R1_ohm : float
        Stator resistance (slope of V(I) over the plateau levels).
    e_inf_V : float
        Alpha-axis voltage error on the plateau (the intercept), V.
    i_A, u_V : numpy.ndarray
        The per-phase inverter-error table, from ``(0, 0)``: phase current, A; voltage lost, V.
    I_A, V_V : numpy.ndarray
        The measured levels: alpha current, A, and commanded alpha voltage, V.
    V_beta_V : numpy.ndarray
        The commanded beta voltage at each level, V.
    gain_b_per_a : float
        The current sensors' relative gain ``g_b/g_a`` (module docstring).
    duration_s : float
        Simulated duration of the test.
    """

    R1_ohm: float
    e_inf_V: float
    i_A: np.ndarray
    u_V: np.ndarray
    I_A: np.ndarray
    V_V: np.ndarray
    duration_s: float
    V_beta_V: np.ndarray
    gain_b_per_a: float


def dc_test(sc, npl: Nameplate, model: dict, T2: float) -> DcResult:
    """Run the standstill DC test on scenario ``sc`` (module docstring).

    Parameters
    ----------
    sc : Scenario
        The user's scenario (its plant, inverter and sensors).
    npl : Nameplate
        What the drive knows.
    model : dict
        The controller's model before the test (``[estimator]`` keys): the test's currents are
        the flux references divided by its ``M_H``.
    T2 : float
        The rotor time constant (the first test's), s: each level lasts :data:`DWELL_T2` of it.

    Returns
    -------
    DcResult
    """
    dwell = DWELL_T2 * T2
    M = model["M_H"]
    points = []
    for k, f in enumerate(LEVELS_PU):
        psi = f * npl.I_rated_A * M
        points += [[k * dwell, psi], [(k + 1) * dwell - 0.5 * npl.Ts_s, psi]]
    t_end = len(LEVELS_PU) * dwell
    scen = test_scenario(
        sc,
        "dc",
        t_end,
        control={**NO_SPEED_LOOP, "speed_feedback": "measured", "flux_ref_Wb": {"points": points}},
        estimator=model,
        plant=HELD_ROTOR,
    )
    res = run_test(scenario=scen, test="dc")
    I_lv, V_lv, Vb_lv = [], [], []
    for k, f in enumerate(LEVELS_PU):
        t1 = (k + 1) * dwell
        t0 = t1 - AVERAGE_FRACTION * dwell
        tm = 0.5 * (t0 + t1)
        _, v, i = window(res, t0, t1, npl.delay)
        _, v1, _ = window(res, t0, tm, npl.delay)
        _, v2, _ = window(res, tm, t1, npl.delay)
        V = float(np.mean(v.real))
        drift = abs(float(np.mean(v2.real) - np.mean(v1.real)))
        scale = max(abs(V), 0.05 * npl.V_phase_V)
        # below the plateau the current controllers limit-cycle around the dead time's
        # step (the level's mean is still its value): only the plateau's levels, which give
        # R1, must be settled to the tolerance
        tol = SETTLED_TOL if f >= PLATEAU_PU else SETTLED_TOL_LOW
        if drift > tol * scale:
            raise CommissioningFailed(
                "dc",
                f"the voltage at {f:g} x rated current did not settle in {dwell:.3g} s "
                f"(it moved by {drift:.3g} V between the halves of the averaging window)",
            )
        if V > 0.95 * npl.v_max:
            raise CommissioningFailed(
                "dc",
                f"{f:g} x rated current needs more than the inverter's {npl.v_max:.4g} V",
            )
        I_lv.append(float(np.mean(i.real)))
        V_lv.append(V)
        Vb_lv.append(float(np.mean(v.imag)))
    I_lv, V_lv = np.array(I_lv), np.array(V_lv)
    target = np.array(LEVELS_PU) * npl.I_rated_A
    short = np.abs(I_lv - target) > 0.02 * npl.I_rated_A
    if short.any():
        k = int(np.argmax(short))
        raise CommissioningFailed(
            "dc",
            f"the current controllers did not reach {target[k]:.3g} A (measured "
            f"{I_lv[k]:.3g} A at {LEVELS_PU[k]:g} x rated current)",
        )
    return _evaluate(I_lv, V_lv, np.array(Vb_lv), t_end, npl)


def unfold(nodes_i: np.ndarray, e: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """The per-phase loss ``u`` at ``nodes_i`` (the first 0) from the alpha-axis errors ``e``
    at ``nodes_i[1:]``: the least-squares solution of ``e_k = (2/3)(u(I_k) + u(I_k/2))``
    (``u`` linear between the nodes) among the tables that rise from ``u(0) = 0`` and never
    fall (a loss that grows with the current until the dead time's plateau), each level
    weighted by ``weight`` (the plateau's levels, fitted together, count more), found as
    non-negative increments (``scipy.optimize.lsq_linear``). At the smallest currents the
    sensors' offsets make the phase currents differ from ``(I, -I/2, -I/2)``: the plain
    level-by-level unfolding then oscillates, the monotone one does not.
    """
    from scipy.optimize import lsq_linear

    n = len(nodes_i)
    basis = np.eye(n)
    A = np.zeros((n - 1, n))
    for k in range(1, n):
        half = np.array([np.interp(0.5 * nodes_i[k], nodes_i, basis[j]) for j in range(n)])
        A[k - 1] = (2.0 / 3.0) * (basis[k] + half)
    steps = np.tril(np.ones((n, n)))[:, 1:]  # u = steps @ d, d >= 0, u(0) = 0
    d = lsq_linear((A @ steps) * weight[:, None], e * weight, bounds=(0.0, np.inf)).x
    return steps @ d


def _evaluate(
    I_lv: np.ndarray, V_lv: np.ndarray, Vb_lv: np.ndarray, duration: float, npl: Nameplate
) -> DcResult:
    """R1 and the plateau from the upper levels; the per-phase table unfolded below; the
    sensors' relative gain from the beta voltage's slope over the upper levels."""
    upper = np.array(LEVELS_PU) >= PLATEAU_PU
    R1, e_inf = np.polyfit(I_lv[upper], V_lv[upper], 1)
    if not R1 > 0.0:
        raise CommissioningFailed(
            "dc", f"the slope of V(I) over the upper levels is {R1:.3g} ohm (not a resistance)"
        )
    resid = V_lv[upper] - (R1 * I_lv[upper] + e_inf)
    if np.max(np.abs(resid)) > 0.02 * max(e_inf, R1 * I_lv[-1]):
        raise CommissioningFailed(
            "dc",
            "V(I) is not a straight line over the upper levels (the inverter's loss has no "
            f"plateau above {PLATEAU_PU:g} x rated current)",
        )
    r = np.polyfit(I_lv[upper], Vb_lv[upper], 1)[0] / R1  # beta slope per alpha slope
    e = V_lv - R1 * I_lv  # alpha-axis error at each level
    e[upper] = e_inf  # the plateau: the fitted intercept, noise averaged over the levels
    nodes_i = np.concatenate(([0.0], I_lv))
    nodes_u = unfold(nodes_i, e, np.where(upper, 10.0, 1.0))
    return DcResult(
        R1_ohm=float(R1),
        e_inf_V=float(e_inf),
        i_A=np.array(nodes_i),
        u_V=np.array(nodes_u),
        I_A=I_lv,
        V_V=V_lv,
        duration_s=duration,
        V_beta_V=Vb_lv,
        gain_b_per_a=float(1.0 / (1.0 - np.sqrt(3.0) * r)),
    )
