"""Acceleration test: the moment of inertia J.

Method (the acceleration test of self-commissioning drives, Schierling 1988; IEC 60034-28
needs no inertia): with the identified model in the controller, the drive magnetises, then
ramps slowly to :data:`LOW_PU` of rated speed, steps its speed reference up to
:data:`HIGH_PU` and back down to :data:`LOW_PU`, with a current limit that holds the
torque current at :data:`TORQUE_PU` x rated torque. While the speed PI is at that limit::

    J a_up = T_up - T_f,    J a_down = T_down - T_f    =>    J = (T_up - T_down)/(a_up - a_down)

with ``a`` the slope of the speed the drive uses (its estimate, or its encoder) fitted from
20 % to 70 % of each step and ``T`` the air-gap torque of the drive's voltage model
(:func:`air_gap_torque`); a friction or load torque ``T_f`` (constant over the steps)
cancels.

Duration: magnetising ``5 T2`` (identified), then each ramp of about ``J dw / T`` (0.6 s on
the Table IV machine) and its settling: the run lasts for a machine of inertia constant up to
:data:`H_MAX_S` (a longer ramp than that is a failure of the test, not of the drive).

What limits the accuracy: the voltage model's torque (``R1`` and the inverter's table enter
the flux, 1-2 % of it at 0.2 x rated speed; the flux's starting value is removed as its mean
over the window, exact for whole turns); the speed estimate's dynamics (a constant lag does
not change the slope; only the middle of each step is fitted). The field-oriented torque
``k_t i_q`` is not used: the estimate's lag in the ramp turns the orientation by 0.1 rad, 15 %
of the torque on the Table IV machine.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imdrive.commission.base import (
    CommissioningFailed,
    Nameplate,
    run_test,
    test_scenario,
    window,
)

#: The speed steps, per unit of rated speed.
HIGH_PU = 0.8
LOW_PU = 0.2
#: The accelerating torque, per unit of rated torque.
TORQUE_PU = 0.5
#: The largest inertia constant ``H = J w_m^2 / (2 P)`` the test's duration allows, s.
H_MAX_S = 1.0
#: The part of each ramp fitted (fractions of the speed step).
FIT_FROM, FIT_TO = 0.2, 0.7
#: The speed PI's zero, rad/s: its integral keeps the output at the limit while the speed
#: error exceeds ``a/PI_ZERO_RAD_S`` (``a``: the acceleration; the back-calculation
#: anti-windup otherwise lets the output leave the limit as soon as the error shrinks).
PI_ZERO_RAD_S = 50.0


@dataclass
class InertiaResult:
    """What the acceleration test found.

    Attributes
    ----------
    J_kgm2 : float
        Moment of inertia.
    torque_constant : float
        ``1.5 n_p (M/L2) psi_r``, N m/A.
    slopes : tuple of float
        Fitted accelerations up and down, mechanical rad/s^2.
    torque : tuple of float
        Mean air-gap torque over each fitted part (:func:`air_gap_torque`), N m.
    windows : tuple of tuple
        The fitted time windows, s.
    duration_s : float
    result : SimulationResult
    """

    J_kgm2: float
    torque_constant: float
    slopes: tuple
    torque: tuple
    windows: tuple
    duration_s: float
    result: object = None


def acceleration_test(sc, npl: Nameplate, model: dict, T2: float, rated_power_W: float, table):
    """Run the acceleration test on scenario ``sc`` with the identified ``model``.

    Parameters
    ----------
    sc : Scenario
    npl : Nameplate
    model : dict
        The identified ``[estimator]`` keys.
    T2 : float
        The identified rotor time constant, s.
    rated_power_W : float
        Rated power (nameplate), W: bounds the test's duration through :data:`H_MAX_S`.
    table : tuple of numpy.ndarray
        The inverter-error table ``(i_A, u_V)``: its plateau is compensated by the dead-time
        feed-forward (so the estimator's voltage is the applied one), the table subtracted
        from the command in the torque's voltage model.
    """
    u_inverter = float(table[1][-1])
    M, L2 = model["M_H"], model["M_H"] + model["Ll2_H"]
    k_t = 1.5 * npl.n_p * M / L2 * npl.psi_rated_Wb
    iq = TORQUE_PU * npl.torque_Nm / k_t
    i_d = npl.psi_rated_Wb / M
    w_rated = npl.speed_rpm * math.pi / 30.0
    dw = (HIGH_PU - LOW_PU) * w_rated
    J_max = 2.0 * H_MAX_S * rated_power_W / w_rated**2
    t_ramp = 2.0 * J_max * HIGH_PU * w_rated / (TORQUE_PU * npl.torque_Nm) + 0.2
    t_mag = 5.0 * T2
    t_up = t_mag + 2.0 * t_ramp  # a slow ramp to LOW_PU, where the estimator is at home
    t_down = t_up + t_ramp
    t_end = t_down + t_ramp
    high, low = HIGH_PU * npl.speed_rpm, LOW_PU * npl.speed_rpm
    ref = [[0, 0], [t_mag, 0], [t_mag + t_ramp, low], [t_up, low], [t_up + 1e-6, high]]
    ref += [[t_down, high], [t_down + 1e-6, low]]
    scen = test_scenario(
        sc,
        "acceleration",
        t_end,
        control={
            "speed_ref_rpm": {"points": ref},
            "current_limit_A": math.hypot(i_d, iq),
            "speed_kp": iq / (0.02 * dw),
            "speed_ki": PI_ZERO_RAD_S * iq / (0.02 * dw),
            "dead_time_compensation": "feedforward",
            "dead_time_compensation_s": u_inverter
            / (sc.inverter.switching_frequency_Hz * npl.Vdc_meas_V),
        },
        estimator=model,
    )
    res = run_test(scen, "acceleration")
    sensorless = sc.control.speed_feedback != "measured"
    speed = res["speed_est_rpm" if sensorless else "speed_rpm"] * math.pi / 30.0
    t = res["time_s"]
    iq_ref = res["iq_ref_A"]
    iq_max = math.sqrt(max(math.hypot(i_d, iq) ** 2 - i_d**2, 0.0))
    fits = []
    for sign, t0, t1, w0, w1 in (
        (1.0, t_up, t_down, low * math.pi / 30.0, high * math.pi / 30.0),
        (-1.0, t_down, t_end, high * math.pi / 30.0, low * math.pi / 30.0),
    ):
        lo_w = w0 + FIT_FROM * (w1 - w0)
        hi_w = w0 + FIT_TO * (w1 - w0)
        between = (speed - lo_w) * (speed - hi_w) <= 0.0
        sel = (t >= t0) & (t < t1) & between & (sign * iq_ref > 0.98 * iq_max)
        if sel.sum() < 20:
            raise CommissioningFailed(
                "acceleration",
                f"the speed did not ramp from {lo_w * 30 / math.pi:.4g} to "
                f"{hi_w * 30 / math.pi:.4g} rpm at the current limit within {t1 - t0:.3g} s "
                f"(an inertia constant above {H_MAX_S:g} s, or a load)",
            )
        a = float(np.polyfit(t[sel], speed[sel], 1)[0])
        win = (float(t[sel][0]), float(t[sel][-1]))
        fits.append((a, air_gap_torque(res, win, npl, model["R1_ohm"], table), win))
    (a1, T1, win1), (a2, T_2, win2) = fits
    if not a1 - a2 > 0.0:
        raise CommissioningFailed("acceleration", "the speed did not follow the torque's sign")
    J = (T1 - T_2) / (a1 - a2)
    return InertiaResult(J, k_t, (a1, a2), (T1, T_2), (win1, win2), t_end, res)


def air_gap_torque(res, win: tuple, npl: Nameplate, R1: float, table) -> float:
    """Mean air-gap torque over ``win`` from the drive's voltage model, N m.

    ``psi_s = integral (v - R1 i) dt`` over the window (``v``: the command less the inverter's
    loss from the table), its unknown starting value removed as the mean over the window (the
    flux turns many times in it: at 0.2-0.8 x rated speed, 10 turns in a 0.3 s ramp), then
    ``T = 1.5 n_p Im(conj(psi_s) i_s)``. Unlike the field-oriented torque ``k_t i_q``, it
    does not depend on the orientation, which the speed estimate's lag in the ramp disturbs
    (0.04-0.1 rad on the Table IV machine: 6-15 % of the torque).
    """
    t, v, i = window(res, win[0], win[1], npl.delay, table)
    flux = np.cumsum((v - R1 * i) * npl.Ts_s)
    flux -= np.mean(flux)
    return float(np.mean(1.5 * npl.n_p * (np.conj(flux) * i).imag))
