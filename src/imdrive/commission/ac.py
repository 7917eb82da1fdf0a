"""Standstill AC test above the rotor corner: the leakage (sigma L1) and R2.

Method (the standstill frequency-response test of Schierling 1988 and of the self-commissioning
literature, e.g. Ruff and Grotstollen 1993; the locked-rotor impedance of IEC 60034-28:2012
measured by the drive at standstill, where single-phase excitation gives no torque): the
current controllers impose, along the alpha axis, a DC bias plus a sinusoid,

    i_alpha = I_dc + I_ac sin(w t),   I_dc = :data:`BIAS_PU` I_m,  I_ac = :data:`AMPLITUDE_PU` I_m

(``I_m``: the rated magnetising current the no-load test measured), at the frequencies
:data:`FREQUENCIES_T2` / T2 (1, 4 and 16 times the rotor corner ``1/T2`` the first test
measured, :mod:`~imdrive.commission.rotor_time`). The bias keeps every phase current away from
zero (phase a between 0.2 and 0.6 ``I_m``, b and c half of it, opposite), so the inverter's loss
is constant and has no component at ``w``: the test needs no inverter model. The impedance
``Z(jw) = V/I`` of the fundamental phasors (with a straight line fitted beside them, which
takes the rest of the bias's flux transient) is fitted (least squares on ``Z`` relative to
``|Z|``) by the T-circuit at standstill with equal leakages (IEC 60034-28's convention when
the design is not known)::

    Z = R1 + j w Ll + j w M (R2 + j w Ll) / (R2 + j w (M + Ll)),    M = L1,0 - Ll

for ``Ll`` and ``R2``, with ``R1`` from the DC test and ``L1,0`` (the unsaturated ``L1``) from
the no-load test's lowest level (the bias and the sinusoid stay below 0.6 x rated flux, where
the incremental inductance is within a few 0.1 % of the secant one of the lowest level). Then
``sigma L1 = L1 - M^2/L1`` with ``L1``, ``M`` at the rated flux.

Why these frequencies: the leakage shows in ``Z`` only where ``w Ll`` is not small against
``R1 + R2``, above the rotor corner. At 0.5-2 x rated slip frequency (the test's former
frequencies, ``w T2`` = 2.2-9 on the 500 hp and 2250 hp machines, 0.7-2.9 on Table IV) ``w Ll``
is 1-7 % of ``|Z|``, so a 1 % error in ``Z`` moved ``Ll`` by 10-40 %; at 1-16 ``/T2`` by 5 %
for a 1 % phase error, 0 % for a 1 % gain error, on every library machine.

The dither: the current controllers close their loop on the ADC's quantised current. Without
noise to spread it, a current that crosses few ADC steps per period lags the quantised one the
controllers impose (the integral acts on a quantised error) by up to half a step: on the 500 hp
and 2250 hp machines, whose magnetising current is 0.22 of rated (and the ADC's range 4.36 x
rated peak), the sinusoid crosses 20 steps and ``Z`` turned by 1-1.5 %, ``sigma L1`` -7...-11
% (a 16-bit ADC, or 0.5 A of sensor noise, removed it: the error is the quantiser's). A
sinusoid of :data:`DITHER_LSB` ADC steps on the flux command (``[flux_injection]``) at
about a quarter of the current controllers' bandwidth spreads the current over the steps
(:func:`dither`; the drive knows its ADC); the fundamental's window holds whole periods of
it, so it leaves no component at ``w``.

Duration: per frequency :data:`SETTLE_T2` = 6 T2 of settling, then whole periods over at
least :data:`MEASURE_T2` = 2 T2 (5 s in all on the Table IV machine, 91 s on the 2250 hp one);
currents up to 0.6 ``I_m``.

What limits the accuracy: the leakage split (with ``Ll1 != Ll2`` the fitted ``R2`` is the
plant's times ``L1/L2``: a few 0.1 % to 2 % for leakages +-30 % apart); the voltage signal is
small (``|Z| I_ac``, a few volts) against the current sensors' noise through the current
controllers, averaged over whole periods; ``R1`` enters ``Re Z`` directly, so an ``R1`` error
``dR1`` moves ``R2`` by about ``dR1 (L2/M)^2 (1 + (w T2)^-2)``; the current sensors' gain
error, which scales ``Z``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imdrive.commission.base import (
    HELD_ROTOR,
    NO_SPEED_LOOP,
    CommissioningFailed,
    Nameplate,
    run_test,
    test_scenario,
    whole_frequency,
    window,
)

#: The test frequencies, in units of the measured rotor corner frequency ``1/T2``.
FREQUENCIES_T2 = (1.0, 4.0, 16.0)
#: The DC bias and the sinusoid's amplitude, per unit of the rated magnetising current.
BIAS_PU = 0.4
AMPLITUDE_PU = 0.2
#: Settling before the measurement, in rotor time constants (measured); then whole periods
#: over at least :data:`MEASURE_T2` rotor time constants and :data:`PERIODS` periods.
SETTLE_T2 = 6.0
MEASURE_T2 = 2.0
PERIODS = 4
#: The dither's amplitude, in steps of the current sensors' ADC, and its frequency, in units
#: of the current controllers' bandwidth (module docstring).
DITHER_LSB = 4.0
DITHER_BANDWIDTH = 0.25


@dataclass
class AcResult:
    """What the AC test found.

    Attributes
    ----------
    Ll_H : float
        Leakage inductance of each winding (equal leakages), H.
    R2_ohm : float
        Rotor resistance (T-circuit, referred to the stator, equal leakages), ohm.
    M0_H : float
        The unsaturated magnetising inductance the fit used, H.
    w : numpy.ndarray
        Test frequencies, rad/s.
    Z : numpy.ndarray of complex
        Measured impedances, ohm.
    Z_fit : numpy.ndarray of complex
        The fitted circuit's, ohm.
    duration_s : float
        Simulated duration.
    """

    Ll_H: float
    R2_ohm: float
    M0_H: float
    w: np.ndarray
    Z: np.ndarray
    Z_fit: np.ndarray
    duration_s: float


def standstill_impedance(w, R1, Ll, M, R2):
    """The T-circuit's impedance at standstill with equal leakages, ohm."""
    jw = 1j * np.asarray(w)
    return R1 + jw * Ll + jw * M * (R2 + jw * Ll) / (R2 + jw * (M + Ll))


def ac_test(
    sc, npl: Nameplate, R1: float, L1_0: float, I_m: float, table, model, T2: float
) -> AcResult:
    """Run the standstill AC test on scenario ``sc`` (module docstring).

    Parameters
    ----------
    sc : Scenario
    npl : Nameplate
    R1 : float
        From the DC test, ohm.
    L1_0 : float
        The unsaturated stator inductance (the no-load test's lowest level), H.
    I_m : float
        The rated magnetising current (peak), A.
    table : tuple of numpy.ndarray
        The inverter-error table (subtracted; constant over the test).
    model : dict
        The controller's model (``[estimator]`` keys): its ``M_H`` turns the bias into a flux
        reference.
    T2 : float
        The rotor time constant (the first test's), s: the frequencies are
        :data:`FREQUENCIES_T2` / T2, the settling :data:`SETTLE_T2` T2.
    """
    I_dc, I_ac = BIAS_PU * I_m, AMPLITUDE_PU * I_m
    settle = SETTLE_T2 * T2
    Z, ws, total = [], [], 0.0
    for x in FREQUENCIES_T2:
        f = whole_frequency(x / (2.0 * math.pi * T2), npl.Ts_s)
        w = 2.0 * math.pi * f
        n_periods = 2 * math.ceil(0.5 * max(PERIODS, MEASURE_T2 * T2 * f))  # even
        t_end = settle + n_periods / f
        scen = test_scenario(
            sc,
            "ac",
            t_end + 2.0 * npl.Ts_s,
            control={
                "speed_feedback": "measured",
                **NO_SPEED_LOOP,
                "flux_ref_Wb": I_dc * model["M_H"],
            },
            injection={
                "amplitude_A": I_ac,
                "frequency_Hz": f,
            },
            flux_injection=dither(sc, I_dc, f),
            estimator=model,
            plant=HELD_ROTOR,
        )
        res = run_test(scen, "ac")
        t, v, i = window(res, settle, t_end, npl.delay, table)
        V = detrended_fundamental(v.real, t, w)
        I = detrended_fundamental(i.real, t, w)
        if not 0.8 < abs(I) / I_ac < 1.2:
            raise CommissioningFailed(
                "ac",
                f"the current controllers imposed {abs(I):.3g} A at {f:.3g} Hz instead of "
                f"{I_ac:.3g} A",
            )
        Z.append(V / I)
        ws.append(w)
        total += t_end
    return _fit(np.array(ws), np.array(Z), R1, L1_0, total)


def dither(sc, I_dc: float, f: float) -> dict:
    """The ``[flux_injection]`` keys of the dither at test frequency ``f`` (Hz) on the bias
    current ``I_dc`` (A): :data:`DITHER_LSB` ADC steps (the drive knows its ADC: ``sensor.
    adc_bits`` and its range) at the odd multiple of ``f/2`` nearest :data:`DITHER_BANDWIDTH`
    x the current controllers' bandwidth, so an even number of the test's periods holds whole
    periods of it; none without an ADC."""
    from imdrive.config.defaults import in_effect

    bits = sc.sensor.adc_bits
    if not bits:
        return {"amplitude": 0.0}
    lsb = 2.0 * in_effect(sc, "sensor.adc_range_A") / 2**bits
    n = max(round(DITHER_BANDWIDTH * sc.control.current_bandwidth_Hz / f - 0.5), 1)
    return {
        "amplitude": min(DITHER_LSB * lsb / I_dc, 0.5),
        "frequency_Hz": (n + 0.5) * f,
        "frequency_pu": None,
    }


def detrended_fundamental(x: np.ndarray, t: np.ndarray, w: float) -> complex:
    """Complex amplitude ``X`` of the component ``Re(X e^{jwt})`` of the real signal ``x``, by
    least squares together with a straight line ``a + b t``: what is left of the bias's flux
    transient (a slow exponential) is taken by the line, not by the sinusoid."""
    tm = t - np.mean(t)
    A = np.column_stack((np.ones_like(tm), tm, np.cos(w * t), -np.sin(w * t)))
    coef, *_ = np.linalg.lstsq(A, x, rcond=None)
    return complex(coef[2], coef[3])


def _fit(w: np.ndarray, Z: np.ndarray, R1: float, L1_0: float, duration: float) -> AcResult:
    """``Ll`` and ``R2`` by least squares on the impedances (relative to ``|Z|``)."""
    from scipy.optimize import least_squares

    def resid(x):
        Ll, R2 = x
        err = (standstill_impedance(w, R1, Ll, L1_0 - Ll, R2) - Z) / np.abs(Z)
        return np.concatenate((err.real, err.imag))

    Zr = Z - R1  # first guess: the highest frequency's reactance is about 2 w Ll
    x0 = (max(0.5 * Zr[-1].imag / w[-1], 1e-3 * L1_0), max(Zr[0].real, 1e-6))
    sol = least_squares(resid, x0, bounds=([1e-6 * L1_0, 1e-9], [0.5 * L1_0, np.inf]))
    Ll, R2 = sol.x
    worst = float(np.max(np.abs(sol.fun)))
    if not sol.success or worst > 0.05:
        raise CommissioningFailed(
            "ac",
            f"the standstill impedances do not fit the T-circuit (largest residual "
            f"{100 * worst:.2g} % of |Z|)",
        )
    Z_fit = standstill_impedance(w, R1, Ll, L1_0 - Ll, R2)
    return AcResult(float(Ll), float(R2), float(L1_0 - Ll), w, Z, Z_fit, duration)
