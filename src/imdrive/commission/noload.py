"""Rotating no-load test at several flux levels: L1 and the magnetising curve Lm(psi_m).

Method (IEC 60034-28:2012, the no-load test; its self-commissioning form in Schierling 1988
and Ruff and Grotstollen, "Identification of the saturated mutual inductance of an asynchronous
motor at standstill by recursive least squares algorithm", EPE 1993, who use the same
magnetising curve in the controller): the uncoupled machine runs on an open-loop V/f voltage
at :data:`FREQUENCY_PU` of its rated frequency; after a slow ramp the voltage steps through
:data:`FLUX_PU` (rated rotor flux). At no load the rotor carries no current (no friction
torque in the model; a real machine's friction adds a slip of a few 1e-4), so at each level
the fundamental phasors of the commanded voltage ``V`` and of the measured current ``I``
give::

    L1 = Im(V / I) / w,     psi_s = L1 |I|,
    Lm = L1 - Ll1,          psi_m = Lm |I|          (i_m = i_s, psi_m and i_s in phase)

The reactive part is the one IEC 60034-28 uses (the no-load reactive power): neither the
stator resistance nor the inverter's loss, in phase with the current, enters it. The DC
test's table is not subtracted here: around each zero crossing of a rotating drive's current
the dead time's loss changes sign later than the measured current does (the current clamps
near zero), so a table of the current's sign puts a part in quadrature into ``V`` (+4 % on
``L1`` at 0.3 x rated flux on a Table IV variant) that the uncorrected loss does not have
(-0.2 %, and -2 % at 0.3 x rated flux).

(``Ll1`` from the standstill AC test, :mod:`imdrive.commission.ac`; the curve is recomputed
once it is known). ``L1`` of the controller is ``L1`` at the rated flux.

Duration: a ramp to the first level's frequency in the time a rotor of inertia constant
:data:`~imdrive.commission.inertia.H_MAX_S` (the heaviest the acceleration test accepts) takes
at :data:`RAMP_TORQUE_PU` x rated torque (4 s on the Table IV machine), then
:data:`DWELL_T2` = 10 rotor time constants (measured by
:mod:`~imdrive.commission.rotor_time`) at each of the 10 levels (14 s in all, on that
machine), twice or four times that where a level has not settled (:func:`noload_test`); the
no-load current, up to about 1.5 x the rated magnetising current at 1.2 x rated flux.

What limits the accuracy: the dead time's loss in quadrature with the current (the
largest error, at the lowest levels: up to 2 % at 0.3 x rated flux, where the current is
smallest; the levels' frequencies are as high as the inverter allows to keep it small); the
phase of the voltage against the current (the computation delay is accounted for); the
leakage split (``Ll1 = Ll2`` assumed, the
IEC 60034-28 convention when the design is not known): an error ``dLl1`` shifts ``psi_m`` by
``dLl1 I`` and ``Lm`` by ``dLl1``; the speed ripple of the unloaded V/f drive at the lowest
levels (each level is refused if its two halves disagree, :data:`SETTLED_TOL`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imdrive.commission.base import (
    CommissioningFailed,
    Nameplate,
    fundamental,
    run_test,
    test_scenario,
    window,
)
from imdrive.commission.inertia import H_MAX_S

#: Each level's frequency gives :data:`VOLTAGE_PU` of the inverter's largest voltage, within
#: ``[FREQUENCY_PU, 1]`` x rated frequency: as high a voltage as the inverter allows, so its
#: loss (whose part in quadrature with the current, from the dead time's distortion around
#: the current's zero crossings, enters ``L1``) is as small a part of it as it can be.
FREQUENCY_PU = 0.5
VOLTAGE_PU = 0.8
#: Fraction of a level spent changing voltage and frequency from the last level's.
CHANGE_FRACTION = 0.2
#: The flux levels, per unit of rated rotor flux, in the order run (from the top: the ramp
#: runs at rated flux).
FLUX_PU = (1.2, 1.1, 1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3)
#: The accelerating torque the ramp from standstill asks of the heaviest rotor the
#: acceleration test accepts, per unit of rated torque: the ramp lasts
#: ``2 H_MAX_S (f/f_rated) / RAMP_TORQUE_PU``.
RAMP_TORQUE_PU = 0.5
#: Time at each level, in rotor time constants (measured); the last
#: :data:`AVERAGE_FRACTION` is averaged (whole periods).
DWELL_T2 = 10.0
AVERAGE_FRACTION = 0.6
#: Largest relative difference of L1 between the two halves of a level's window.
SETTLED_TOL = 3e-2
#: How many times the test runs again with twice the dwell while a level has not settled.
DWELL_DOUBLINGS = 2


@dataclass
class NoLoadResult:
    """What the no-load test measured.

    Attributes
    ----------
    w_e : numpy.ndarray
        The electrical frequency of each level, rad/s.
    V, I : numpy.ndarray of complex
        Fundamental phasors (space-vector amplitude) of the commanded voltage, V, and the
        measured current, A, at each level (in :data:`FLUX_PU` order).
    R1_ohm : float
        The stator resistance the flux was computed with.
    duration_s : float
        Simulated duration.
    result : SimulationResult
        The test's run (for the figures).
    """

    w_e: float
    V: np.ndarray
    I: np.ndarray
    R1_ohm: float
    duration_s: float
    result: object = None

    @property
    def L1_H(self) -> np.ndarray:
        """Stator self-inductance at each level, ``Im(V/I)/w``, H: the reactive part, which
        neither ``R1`` nor the inverter's loss (in phase with the current) enters."""
        return (self.V / self.I).imag / self.w_e

    @property
    def psi_s(self) -> np.ndarray:
        """Stator-flux magnitude at each level, ``L1 |I|``, Wb."""
        return self.L1_H * np.abs(self.I)

    def magnetising_curve(self, Ll1: float) -> tuple[np.ndarray, np.ndarray]:
        """``(psi_m, Lm)`` at each level, ascending in flux, for a stator leakage ``Ll1``."""
        Lm = self.L1_H - Ll1
        psi_m = Lm * np.abs(self.I)
        order = np.argsort(psi_m)
        return psi_m[order], Lm[order]

    def at_flux(self, psi_m: float, Ll1: float) -> tuple[float, float]:
        """``(Lm, i_m)`` at magnetising flux ``psi_m`` (Wb): the secant inductance (H)
        interpolated in the curve, and the magnetising current ``psi_m/Lm`` (A, peak)."""
        flux, Lm = self.magnetising_curve(Ll1)
        L = float(np.interp(psi_m, flux, Lm))
        return L, psi_m / L

    @property
    def L1_lowest(self) -> float:
        """L1 at the lowest flux level (the unsaturated one), H."""
        return float(self.L1_H[int(np.argmin(np.abs(self.I)))])


class _Unsettled(Exception):
    """A level whose two half-windows disagree by more than :data:`SETTLED_TOL`."""


def noload_test(
    sc, npl: Nameplate, R1: float, table: tuple, model: dict, T2: float
) -> NoLoadResult:
    """Run the rotating no-load test on scenario ``sc`` (module docstring), measuring until
    every level has settled: a level that has not after :data:`DWELL_T2` rotor time constants
    runs the test again with twice the dwell, up to :data:`DWELL_DOUBLINGS` times, before
    it fails. (On a Krause 50 hp plant of the accuracy table, its parameters scaled by up
    to 30 %, L1 at 0.8 x rated flux moved 3.6 % between the two halves of a 10 T2 level, the
    unloaded V/f machine's speed still swinging; at 20 T2 it was settled and L1 within 0.02
    %. A fixed 20 T2 would double the test for every machine.)

    Parameters and the result: :func:`_noload_run`; ``T2``: the rotor time constant (the
    first test's), s.
    """
    for k in range(DWELL_DOUBLINGS + 1):
        try:
            return _noload_run(sc, npl, R1, table, model, DWELL_T2 * T2 * 2**k)
        except _Unsettled as exc:
            why = str(exc)
    raise CommissioningFailed("no-load", why)


def _noload_run(
    sc, npl: Nameplate, R1: float, table: tuple, model: dict, dwell: float
) -> NoLoadResult:
    """The no-load test with ``dwell`` seconds at each level (module docstring).

    Parameters
    ----------
    sc : Scenario
        The user's scenario.
    npl : Nameplate
        What the drive knows.
    R1 : float
        The DC test's stator resistance, ohm.
    table : tuple of numpy.ndarray
        The DC test's inverter-error table ``(i_A, u_V)``: its plateau is compensated in the
        command by the dead-time feed-forward (so each level's flux is near its target).
    model : dict
        The controller's model (``[estimator]`` keys; unused by the open-loop voltage).
    dwell : float
        Time at each level, s.

    Raises
    ------
    _Unsettled
        A level that did not settle.
    """
    to_ll = math.sqrt(1.5)  # phase peak -> line-to-line rms
    boost = R1 * 0.3 * npl.I_rated_A  # the stator's drop at a typical magnetising current
    w_r = npl.w_rated
    f_lv = [
        npl.f_rated_Hz
        * min(1.0, max(FREQUENCY_PU, VOLTAGE_PU * npl.v_max / (x * npl.psi_rated_Wb * w_r)))
        for x in FLUX_PU
    ]
    V_lv = [
        x * npl.psi_rated_Wb * 2.0 * math.pi * f + boost for x, f in zip(FLUX_PU, f_lv, strict=True)
    ]
    ramp = 2.0 * H_MAX_S * (f_lv[0] / npl.f_rated_Hz) / RAMP_TORQUE_PU
    if max(V_lv) > 0.95 * npl.v_max:
        k = int(np.argmax(V_lv))
        raise CommissioningFailed(
            "no-load",
            f"{FLUX_PU[k]:g} x rated flux at {f_lv[k]:.3g} Hz needs {V_lv[k]:.4g} V, more than "
            f"the inverter's {npl.v_max:.4g} V",
        )
    v_pts = [[0.0, boost * to_ll], [ramp, V_lv[0] * to_ll]]
    f_pts = [[0.0, 0.0], [ramp, f_lv[0]]]
    for k, (V, f) in enumerate(zip(V_lv, f_lv, strict=True)):
        t0 = ramp + k * dwell
        t_on = t0 + (CHANGE_FRACTION * dwell if k else 0.0)
        v_pts += [[t_on, V * to_ll], [t0 + dwell, V * to_ll]]
        f_pts += [[t_on, f], [t0 + dwell, f]]
    t_end = ramp + len(FLUX_PU) * dwell
    u_plateau = float(table[1][-1])
    f_sw = sc.inverter.switching_frequency_Hz
    scen = test_scenario(
        sc,
        "no-load",
        t_end,
        drive={"mode": "open-loop"},
        open_loop={
            "voltage_V": {"points": v_pts},
            "frequency_Hz": {"points": f_pts},
            "vf_ramp_s": 0.0,
        },
        control={
            "dead_time_compensation": "feedforward",
            "dead_time_compensation_s": u_plateau / (f_sw * npl.Vdc_meas_V),
        },
        estimator=model,
    )
    res = run_test(scen, "no-load")
    V_ph, I_ph, w_lv = [], [], []
    for k, flux in enumerate(FLUX_PU):
        w = 2.0 * math.pi * f_lv[k]
        period = 1.0 / f_lv[k]
        t1 = ramp + (k + 1) * dwell
        n = max(int(AVERAGE_FRACTION * dwell / period) // 2 * 2, 2)
        t0 = t1 - n * period
        tm = t1 - (n // 2) * period
        halves = []
        for a, b in ((t0, tm), (tm, t1)):
            t, v, i = window(res, a, b, npl.delay)
            halves.append((fundamental(v, t, w), fundamental(i, t, w)))
        L1s = [(V / I).imag / w for V, I in halves]
        if abs(L1s[1] - L1s[0]) > SETTLED_TOL * L1s[1]:
            raise _Unsettled(
                f"at {flux:g} x rated flux the machine did not settle in {dwell:.3g} s (L1 "
                f"moved by {100 * abs(L1s[1] / L1s[0] - 1):.2g} % between two halves of the "
                "window)",
            )
        t, v, i = window(res, t0, t1, npl.delay)
        V_ph.append(fundamental(v, t, w))
        I_ph.append(fundamental(i, t, w))
        w_lv.append(w)
    return NoLoadResult(np.array(w_lv), np.array(V_ph), np.array(I_ph), R1, t_end, res)
