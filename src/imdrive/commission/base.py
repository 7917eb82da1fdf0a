"""Common ground of the identification run: what the drive knows before it starts, the test
scenarios built from the user's, and the signals a drive sees.

A commissioning drive knows its nameplate (rated voltage, frequency, power, pole pairs and,
when the plate gives them, current, speed, torque, efficiency, power factor), its DC link
(through its own sensor), its control period and computation delay; it sees its measured
currents and the voltages it commands. Currents a test imposes are stated in per-unit of the
nameplate (:class:`Nameplate`); durations and frequencies in units of the rotor time constant
``T2`` the first test measures (:mod:`~imdrive.commission.rotor_time`), never of the
nameplate's slip (which is missing from many plates, and only sets ``T2`` to within a factor of
4 between a 3 hp and a 2 MW machine).

The plant's parameters are never read here: a test scenario's controller model
(``[estimator]``) is set explicitly, first from per-unit guesses (:func:`guess_model`), then
from what the earlier tests identified. A nameplate that lacks the rated current is completed
from its power and voltage with the efficiency and power factor it gives, or
:data:`TYPICAL_EFFICIENCY_PF`; one that lacks the speed, from its torque, or the synchronous
speed (:func:`nameplate`: ``sources`` says which).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.run.simulate import simulate


class CommissioningFailed(RuntimeError):
    """A test of the identification run did not give a usable result.

    Parameters
    ----------
    test : str
        Which test (``"dc"``, ``"no-load"``, ``"ac"``, ``"acceleration"``).
    reason : str
        Why, in one line (what was expected, what was measured).
    """

    def __init__(self, test: str, reason: str):
        self.test = test
        self.reason = reason
        super().__init__(f"commissioning test {test!r} did not converge: {reason}")


#: The product efficiency x power factor assumed when the nameplate gives neither the rated
#: current nor both of them: 0.8 (4-pole IEC motors: about 0.7 at 2 kW, 0.8 at 40 kW, 0.85 at
#: 400 kW). It sets only the test currents (in per-unit of rated), which tolerate +-20 %.
TYPICAL_EFFICIENCY_PF = 0.8


@dataclass(frozen=True)
class Nameplate:
    """What the drive knows before it identifies anything (SI units; currents peak).

    Attributes
    ----------
    I_rated_A : float
        Rated current, peak (phase), A.
    f_rated_Hz, w_rated : float
        Rated frequency, Hz, and electrical rad/s.
    V_phase_V : float
        Rated phase voltage, peak, V.
    psi_rated_Wb : float
        Rated rotor flux (the scenario's flux reference at its start), Wb.
    n_p : int
        Pole pairs.
    torque_Nm, speed_rpm : float
        Rated torque, N m, and speed, rpm.
    Vdc_meas_V : float
        The DC link as the drive measures it, V; ``v_max = Vdc_meas/sqrt 3``.
    Ts_s : float
        Control period, s.
    delay : int
        Computation delay, periods.
    power_W : float
        Rated power, W.
    sources : dict
        Where ``current``, ``speed`` and ``torque`` came from (``"nameplate"`` or the rule).
    """

    I_rated_A: float
    f_rated_Hz: float
    w_rated: float
    V_phase_V: float
    psi_rated_Wb: float
    n_p: int
    torque_Nm: float
    speed_rpm: float
    Vdc_meas_V: float
    Ts_s: float
    delay: int
    power_W: float = 0.0
    sources: dict = field(default_factory=dict)

    @property
    def v_max(self) -> float:
        """The largest voltage vector the drive can command, ``Vdc_meas/sqrt 3``, V."""
        return self.Vdc_meas_V / math.sqrt(3.0)

    @property
    def Z_base(self) -> float:
        """Base impedance, rated phase voltage over rated current, ohm."""
        return self.V_phase_V / self.I_rated_A


def nameplate(sc: Scenario) -> Nameplate:
    """The nameplate and drive data of scenario ``sc``: the machine's nameplate fields only.

    Rated current: the plate's; else ``P / (sqrt 3 V eta cos phi)`` with the plate's
    efficiency and power factor, each :data:`TYPICAL_EFFICIENCY_PF` ** 0.5 when missing.
    Rated speed: the plate's; else ``P / T`` from its torque; else the synchronous speed
    ``60 f / n_p`` (the acceleration test's speeds are fractions of it). Rated torque: the
    plate's; else ``P / w_m``. Nothing is read from the plant's circuit (a real drive has
    only its nameplate), unlike :func:`imdrive.config.rated.rated_point`, which completes a
    nameplate from the circuit.
    """
    m = sc.machine
    P, V, f = m.rated_power_W, m.rated_voltage_V, m.rated_frequency_Hz
    src = {}
    if m.rated_current_rms_A is not None:
        I_rms, src["current"] = m.rated_current_rms_A, "nameplate"
    else:
        typ = math.sqrt(TYPICAL_EFFICIENCY_PF)
        eta = m.rated_efficiency if m.rated_efficiency is not None else typ
        pf = m.rated_power_factor if m.rated_power_factor is not None else typ
        I_rms = P / (math.sqrt(3.0) * V * eta * pf)
        src["current"] = f"P / (sqrt 3 V eta cos phi), eta cos phi = {eta * pf:.3g}"
    n_sync = 60.0 * f / m.pole_pairs
    if m.rated_speed_rpm is not None:
        speed, src["speed"] = m.rated_speed_rpm, "nameplate"
    elif m.rated_torque_Nm is not None:
        speed, src["speed"] = min(P / m.rated_torque_Nm * 30.0 / math.pi, n_sync), "P / T"
    else:
        speed, src["speed"] = n_sync, "synchronous (not on the nameplate)"
    if m.rated_torque_Nm is not None:
        torque, src["torque"] = m.rated_torque_Nm, "nameplate"
    else:
        torque, src["torque"] = P / (speed * math.pi / 30.0), "P / w_m"
    psi = sc.control.flux_ref_Wb.points[0][1] if sc.control.flux_ref_Wb else m.rated_flux_Wb
    return Nameplate(
        I_rated_A=math.sqrt(2.0) * I_rms,
        f_rated_Hz=f,
        w_rated=2.0 * math.pi * f,
        V_phase_V=V * math.sqrt(2.0 / 3.0),
        psi_rated_Wb=psi,
        n_p=m.pole_pairs,
        torque_Nm=torque,
        speed_rpm=speed,
        Vdc_meas_V=sc.sensor.vdc_gain * sc.inverter.Vdc_V,
        Ts_s=sc.simulation.Ts_s,
        delay=sc.control.delay_periods,
        power_W=P,
        sources=src,
    )


def guess_model(npl: Nameplate) -> dict:
    """The controller's model before any test, in per-unit of the nameplate: ``R1 = R2 =
    0.04 Z_b``, leakages ``0.06 Z_b/w``, ``M = 1.7 Z_b/w`` (typical of 1-100 kW machines).

    Only the current controllers' gains of the standstill tests depend on it (the tests
    impose currents, whatever the model); ``[estimator]`` keys.
    """
    Zb, w = npl.Z_base, npl.w_rated
    return {
        "R1_ohm": 0.04 * Zb,
        "R2_ohm": 0.04 * Zb,
        "Ll1_H": 0.06 * Zb / w,
        "Ll2_H": 0.06 * Zb / w,
        "M_H": 1.7 * Zb / w,
    }


def check_commissionable(sc: Scenario) -> None:
    """Refuse, in one line, a scenario the identification run cannot handle."""
    if sc.drive.mode != "vector":
        raise ConfigError(
            "drive.mode",
            f'is "{sc.drive.mode}": commissioning identifies the model of a field-oriented '
            'controller, and an open-loop drive has none (set drive.mode = "vector")',
        )
    npl = nameplate(sc)
    need = 1.1 * npl.V_phase_V * 0.5 / 0.85  # the no-load test's top level, with headroom
    if npl.v_max < need:
        raise ConfigError(
            "inverter.Vdc_V",
            f"the DC link ({npl.Vdc_meas_V:.4g} V measured) gives at most {npl.v_max:.4g} V, "
            f"too low to reach the no-load test's 1.1 x rated flux at half the rated "
            f"frequency (needs {need:.4g} V: Vdc >= {need * math.sqrt(3.0):.4g} V)",
        )


def test_scenario(sc: Scenario, test: str, t_end: float, **sections) -> Scenario:
    """A test's scenario: the user's plant, inverter and sensors, the test's controller.

    Every non-ideality of ``sc`` stays (inverter model, dead time, drops, delay, sensors,
    saturation, thermal model). The machine is uncoupled from its load (no load torque), the
    drive does not sequence (no premagnetisation, no torque-limited ramp: the test's profiles
    are followed as given), the compensator, injection, field weakening and dead-time
    compensation are off unless the test sets them, the controller's model is the constant
    one (no ``[controller_model]`` tables: they are what commissioning identifies), the log
    keeps every period.
    ``sections``: ``{section: {key: value}}`` applied last.
    """
    d = sc.to_dict()
    d["name"] = f"{sc.name[:80]}-commission-{test}"
    d["controller_model"] = {}  # uncommissioned: a scenario already commissioned starts over
    # the test's own duty cycle: no load, and neither profile's per-unit twin (it would take
    # the place of the test's speed_ref_rpm and torque_Nm: the sensorless preset's rated
    # load step landed in the no-load test)
    d["load"].update(torque_Nm=0.0, torque_pu=None, viscous_Nms=0.0, fan_Nms2=0.0)
    # R2 tracking and its signals: every key at its default (off), so that no setting of the
    # user's (injection.frequency_pu, headroom_voltage, ...) changes what a test imposes
    d["compensator"] = {}
    d["injection"] = {}
    d["flux_injection"] = {}
    d["mras"].update(R1_standstill=False, R1_rate_per_s=0.0, R1_rate_pu=None)
    d["afo"]["R1_adaptation"] = False
    d["control"].update(
        field_weakening=False,
        dead_time_compensation="none",
        speed_kp=None,
        speed_ki=None,
        current_kp=None,
        current_ki=None,
        flux_ref_Wb=None,
        speed_ref_rpm=0.0,
        speed_ref_pu=None,
        # a test's timeline is its own: not premagnetised by the drive (each test waits for
        # its build-up in the rotor time constants it measured, not the guessed model's), no
        # ramp followed at a torque limit (the acceleration test sets its own current limit)
        premagnetise_T2=0.0,
        ramp_torque_limit=False,
    )
    for key in ("R1_ratio", "R2_ratio", "M_ratio"):
        d["estimator"][key] = None
    d["estimator"]["R2_adaptation"] = "compensator"
    d["simulation"].update(
        t_end_s=t_end,
        tracking_windows=None,  # a test's length is its own
        log_every=1,
        lost_control_rpm=0.0,
        divergence_current_A=None,
    )
    for section, values in sections.items():
        d.setdefault(section, {}).update(values)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Scenario.from_dict(d)


def switched_off(sc: Scenario) -> list[str]:
    """What the user's scenario has on that the tests run without (:func:`test_scenario`),
    one line each (``key: why``), for the console."""
    out = []
    inj, comp, ctl, mras = sc.injection, sc.compensator, sc.control, sc.mras
    if comp.enabled:
        out.append("compensator.enabled: R2 tracking; R2 is what commissioning identifies")
    if (inj.amplitude_A or 0.0) > 0.0 or (inj.amplitude_pu or 0.0) > 0.0:
        out.append("injection: R2 tracking's signal; the AC test imposes its own")
    if sc.flux_injection.amplitude > 0.0:
        out.append("flux_injection: the AC test uses its own (a dither)")
    if ctl.field_weakening:
        out.append("control.field_weakening: no test runs above base speed")
    if ctl.dead_time_compensation != "none":
        out.append(
            "control.dead_time_compensation: the tests measure the inverter's error "
            "(compensating it from the DC test's table where they need to)"
        )
    if mras.R1_standstill:
        out.append("mras.R1_standstill: R1 is what the DC test identifies")
    if mras.R1_rate_per_s > 0.0 or mras.R1_rate_pu is not None:
        out.append("mras.R1_rate_pu/R1_rate_per_s (online R1): the tests hold their model")
    if sc.afo.R1_adaptation:
        out.append("afo.R1_adaptation: the tests hold their model")
    if sc.estimator.R2_adaptation != "compensator":
        out.append(
            f'estimator.R2_adaptation = "{sc.estimator.R2_adaptation}": the tests hold their model'
        )
    cm = sc.controller_model
    if cm.uses_magnetising_curve or cm.uses_inverter_error:
        out.append("[controller_model]: its tables are what commissioning identifies")
    return out


#: The speed loop of a standstill test: no torque current (a gain of 1e-12 A per rad/s, no
#: integral; ``[control]`` keys), so the controller's angle stays where it starts, on alpha.
NO_SPEED_LOOP = {"speed_kp": 1e-12, "speed_ki": 0.0, "speed_ref_rpm": 0.0}
#: The plant of a standstill test: the rotor held still (``[plant]`` keys). The tests make no
#: torque but the few mN m of the current sensors' errors, which a real machine's static
#: friction holds; the model has no static friction, and a rotor creeping by a fraction of a
#: rpm would turn the measured-speed controller's angle away from alpha.
HELD_ROTOR = {"speed_mode": "imposed", "imposed_speed_rpm": 0.0}


def run_test(scenario: Scenario, test: str):
    """Simulate a test's scenario; a diverged run is a :class:`CommissioningFailed`."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = simulate(scenario)
    if res.diverged:
        raise CommissioningFailed(test, f"the drive diverged ({res.divergence_message})")
    return res


def known_voltage(res, delay: int) -> tuple[np.ndarray, np.ndarray]:
    """The voltage the drive commanded over each period, aligned with its current samples.

    The logged reference of sample ``k`` acts over ``[t_{k+delay}, t_{k+delay+1})``; returned:
    the voltage acting over ``[t_k, t_k+1)`` (alpha + j beta, V) and the mean of the two
    current samples that bracket that period (A), both of length ``n - 1 - delay``.
    """
    v = res["v_ref_alpha_V"] + 1j * res["v_ref_beta_V"]
    i = res["i_alpha_meas_A"] + 1j * res["i_beta_meas_A"]
    n = len(v)
    v_act = v[: n - 1 - delay]
    i_mid = 0.5 * (i[delay : n - 1] + i[delay + 1 : n])
    return v_act, i_mid


def phase_currents(i_ab: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Phase currents a, b, c of stationary-frame currents (amplitude-invariant Clarke)."""
    a = i_ab.real
    b = -0.5 * i_ab.real + (math.sqrt(3.0) / 2.0) * i_ab.imag
    return a, b, -a - b


def inverter_error_ab(i_ab: np.ndarray, table_i: np.ndarray, table_u: np.ndarray) -> np.ndarray:
    """The voltage the inverter loses at currents ``i_ab``, stationary frame, V.

    Each phase loses ``sgn(i_x) u(|i_x|)`` (``u`` interpolated in the table, held past its
    last node); the loss vector is their Clarke transform (the zero sequence drops out).
    """
    ua, ub, uc = (np.sign(x) * np.interp(np.abs(x), table_i, table_u) for x in phase_currents(i_ab))
    return (2.0 / 3.0) * (ua - 0.5 * ub - 0.5 * uc) + 1j * (ub - uc) / math.sqrt(3.0)


def window(res, t0: float, t1: float, delay: int, table=None):
    """Time, applied-voltage estimate and measured current over ``[t0, t1)``.

    The voltage is the command acting over each period (:func:`known_voltage`) less the
    inverter's loss from the identified table ``(i_A, u_V)`` at the period's current, if
    given. Returns ``(t, v_ab, i_ab)``; ``t`` is the middle of the period the voltage acts
    over.
    """
    v, i = known_voltage(res, delay)
    time = res["time_s"]
    t = time[delay : delay + len(v)] + 0.5 * (time[1] - time[0])
    sel = (t >= t0) & (t < t1)
    v, i, t = v[sel], i[sel], t[sel]
    if table is not None:
        v = v - inverter_error_ab(i, *table)
    return t, v, i


def fundamental(x: np.ndarray, t: np.ndarray, w: float) -> complex:
    """Complex amplitude of the component of ``x`` at ``w`` rad/s (the window should hold
    whole periods): for a space vector ``x = X e^{jwt}``, ``X``; for a real ``x = Re(X
    e^{jwt})``, ``X`` (twice the mean of ``x e^{-jwt}``)."""
    rot = np.exp(-1j * w * t)
    if np.iscomplexobj(x):
        return complex(np.mean(x * rot))
    return complex(2.0 * np.mean(x * rot))


def whole_frequency(f: float, Ts: float) -> float:
    """``f`` moved to the nearest frequency with a whole number of control periods."""
    n = max(round(1.0 / (f * Ts)), 2)
    return 1.0 / (n * Ts)
