"""Settings in per-unit of the machine, resolved to the SI values the blocks run on.

A scenario may state a machine-dependent setting in per-unit of the machine instead of an
absolute value, so it stays tuned when ``[machine]`` changes:

==========================================  ===============================================
per-unit key                                SI value
==========================================  ===============================================
``estimator.R1_ratio``, ``R2_ratio``,       ``ratio x`` the plant's R1, R2, M (the
``M_ratio``                                 controller's starting model)
``compensator.R2_min_ratio``, ``_max_``     ``ratio x R2_hat(0)`` (default 0.5 and 2)
``compensator.G_CR_pu``                     ``G_CR_pu x R2_hat(0)``, ohm per output level
``compensator.gain_E_pu`` (E and DE)       ``gain / psi_rated``, 1/Wb
``injection.amplitude_pu``                  ``amplitude_pu x psi_rated / M``, A (peak)
``injection.frequency_pu`` (``2_``, ``3_``) ``pu x R2_hat(0) / (2 pi L2_hat)``, Hz, rounded
                                            to whole control periods
``compensator.gate_band_pu``                ``pu x`` the first injection frequency, Hz
``compensator.gate_speed_pu``               ``pu x`` the rated slip speed, rpm
``compensator.gate_iq_pu``                  ``pu x machine.rated_current_A``, A
``inverter.Vdc_V`` unset                    ``sqrt(2) x rated line voltage`` (the scenario);
                                            the voltage limit is ``Vdc / sqrt(3)``
``control.current_limit_A`` unset           ``1.5 x`` the rated peak current
                                            (:func:`current_limit_A`)
``simulation.divergence_current_A`` unset   ``70 x`` the rated peak current
``compensator.thermal_rise_K``              rotor thermal resistance ``rise / P_r,rated``,
                                            K/W (:func:`rotor_thermal_resistance`)
``mras.acceleration_tracking`` unset        on when the type-1 MRAS's lag at the rated
                                            acceleration exceeds ``0.5 / T2``
                                            (:func:`mras_ramp_lag_pu`), and when the
                                            speed reference goes above ``1.1 x`` the
                                            rated speed with field weakening on
                                            (:func:`mras_type2_for_field_weakening`)
``mras.acceleration_tracking_from_pu``      ``pu x`` the rated stator frequency
``mras.R1_rate_pu``                         ``pu x`` the rotor corner ``R2 / L2``, 1/s
``mras.R1_max_freq_pu`` (default 0.5)       ``pu x`` the rated stator frequency, Hz
``sensor.adc_range_pu``,                    ``pu x`` the rated peak current, A; unset (and
``inverter.sign_band_pu``                   the absolute twin unset): Table IV's 50 A, 0.2 A
                                            scaled by it (:func:`adc_range_A`,
                                            :func:`sign_band_A`)
==========================================  ===============================================

A per-unit key and its absolute twin are one setting: :data:`imdrive.config.pairs.PAIRS`
declares every pair once, and an override of one member clears the other (see
:mod:`imdrive.config.pairs`).
The EKF's noise, the plant's thermal resistances, the flux-command injection's frequency
and the adaptive flux observer's resistance rates are resolved in
:mod:`imdrive.config.scaled` (this module's size); the compensator's step, gains and gate
thresholds, unset, are the paper's Table IV numbers scaled to the machine
(:mod:`imdrive.config.compensator_gains`).

``psi_rated`` is :attr:`~imdrive.config.machine.MachineParams.rated_flux_Wb` (the no-load
rotor flux at rated voltage and frequency) and ``psi_rated / M`` the rated magnetising
current. :func:`resolve` is the one place these are turned into SI values: the scenario's
checks and the drive's records both use it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from imdrive.config.table_iv import table_iv_scaled
from imdrive.errors import ConfigError


@dataclass(frozen=True)
class Resolved:
    """The SI values of the settings that may be given in per-unit.

    Attributes
    ----------
    R1_hat, R2_hat, M_hat : float
        The controller's starting R1, R2 (ohm) and M (H).
    Ll1_hat, Ll2_hat : float
        Its leakage inductances, H.
    R2_min, R2_max : float
        Clamps of R2_hat, ohm.
    G_CR : float
        R2_hat step per output level, ohm.
    gain_E, gain_DE : float
        Input scalings of the compensator, 1/Wb.
    inj_amp : float
        Injection amplitude, A (peak).
    inj_f1, inj_f2, inj_f3 : float
        Injection frequency and its harmonics 2 f, 3 f of the gating's schedule, Hz.
    gate_band : float
        The gating's band around the stator frequency, Hz.
    gate_speed_rpm, gate_iq_A : float
        The gating's speed (rpm) and iq* (A) thresholds of a transient.
    psi_rated : float
        The machine's rated rotor flux, Wb (``machine.rated_flux_Wb``).
    I_rated : float
        The machine's rated current that scales the limits, A (``machine.rated_current_A``).
    speed_bandwidth_Hz : float
        The speed loop's bandwidth, Hz (:func:`speed_bandwidth_Hz`).
    divergence_speed_rpm : float
        The speed that stops a diverging run, rpm (:func:`divergence_speed_rpm`).
    n_comp : int
        The compensator's decision period, control periods
        (:func:`~imdrive.config.compensator.decision_period_steps`).
    sigma, T2_s : float
        The machine's leakage factor and rotor time constant, s.
    v_max_V : float
        The largest phase voltage the inverter can apply, V (``inverter.v_max_V``).
    model_curve, model_inverter_error : bool
        Whether the controller uses ``[controller_model]``'s magnetising curve and its
        inverter-error table.
    current_limit_A, divergence_current_A : float
        The controller's current limit and the current that stops a diverging run, A
        (:func:`current_limit_A`, :func:`divergence_current_A`).
    sat_curve : tuple of float
        The plant's magnetising curve ``(Lm0, psi_sat, S)``
        (:meth:`~imdrive.config.plant.SaturationSettings.curve`).
    rotor_Rth : float
        The rotor thermal model's thermal resistance, K/W (:func:`rotor_thermal_resistance`;
        NaN when the model is off).
    """

    R1_hat: float
    R2_hat: float
    M_hat: float
    Ll1_hat: float
    Ll2_hat: float
    R2_min: float
    R2_max: float
    G_CR: float
    gain_E: float
    gain_DE: float
    inj_amp: float
    inj_f1: float
    inj_f2: float
    inj_f3: float
    gate_band: float
    gate_speed_rpm: float
    gate_iq_A: float
    psi_rated: float = math.nan
    I_rated: float = math.nan
    speed_bandwidth_Hz: float = math.nan
    divergence_speed_rpm: float = math.nan
    n_comp: int = 1
    sigma: float = math.nan
    T2_s: float = math.nan
    v_max_V: float = math.nan
    model_curve: bool = False
    model_inverter_error: bool = False
    current_limit_A: float = math.nan
    divergence_current_A: float = math.nan
    rotor_Rth: float = math.nan
    sat_curve: tuple = (math.nan, math.nan, math.nan)


def _whole_periods(f: float, Ts: float, multiple: int = 1) -> float:
    """``f`` moved to the nearest frequency whose period is a whole number of ``Ts``, that
    number a multiple of ``multiple`` (2 was for the adaptive step law's half-period decisions,
    removed in 0.2)."""
    n = max(multiple * round(1.0 / (f * Ts * multiple)), multiple)
    return 1.0 / (n * Ts)


def _one_of(absolute, ratio, base: float, names: tuple[str, str]):
    if absolute is not None and ratio is not None:
        raise ConfigError(names[1], f"set {names[0]} or {names[1]}, not both")
    if ratio is not None:
        return ratio * base
    return absolute


def resolve(sc) -> Resolved:
    """The SI values of scenario ``sc``'s per-unit-capable settings (module docstring).

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    Resolved

    Raises
    ------
    ConfigError
        An absolute value and its per-unit twin both set (naming the per-unit key).
    """
    memo = getattr(sc, "_perunit_resolved", None)  # a scenario is frozen: resolve it once
    if memo is not None:
        return memo
    out = _resolve(sc)
    try:
        object.__setattr__(sc, "_perunit_resolved", out)
    except (AttributeError, TypeError):  # not a Scenario (a stand-in in a test): no memo
        pass
    return out


def _resolve(sc) -> Resolved:
    m = sc.machine
    est = sc.estimator
    R1 = _one_of(est.R1_ohm, est.R1_ratio, m.R1_ohm, ("estimator.R1_ohm", "estimator.R1_ratio"))
    R2 = _one_of(est.R2_ohm, est.R2_ratio, m.R2_ohm, ("estimator.R2_ohm", "estimator.R2_ratio"))
    M = _one_of(est.M_H, est.M_ratio, m.M_H, ("estimator.M_H", "estimator.M_ratio"))
    R1 = m.R1_ohm if R1 is None else R1
    R2 = m.R2_ohm if R2 is None else R2
    M = m.M_H if M is None else M
    comp = sc.compensator
    lo = _one_of(
        comp.R2_min_ohm,
        comp.R2_min_ratio,
        R2,
        ("compensator.R2_min_ohm", "compensator.R2_min_ratio"),
    )
    hi = _one_of(
        comp.R2_max_ohm,
        comp.R2_max_ratio,
        R2,
        ("compensator.R2_max_ohm", "compensator.R2_max_ratio"),
    )
    psi = m.rated_flux_Wb
    inj = sc.injection
    if inj.frequency_pu is not None:
        L2_hat = (est.Ll2_H if est.Ll2_H is not None else m.Ll2_H) + M
        f_corner = R2 / (2.0 * math.pi * L2_hat)
        Ts = sc.simulation.Ts_s
        f1 = _whole_periods(inj.frequency_pu * f_corner, Ts)
    else:
        from imdrive.config.compensator_gains import injection_frequency_Hz

        f1 = injection_frequency_Hz(inj, m, sc.simulation.Ts_s, False)
    # the gating's schedule: harmonics of the first (config/compensator.py HARMONICS)
    f2, f3 = 2.0 * f1, 3.0 * f1
    from imdrive.config.compensator_gains import compensator_gains

    g = compensator_gains(comp, m, R2, f1)
    I_rated = m.rated_current_A
    from imdrive.config.compensator import decision_period_steps

    r = Resolved(
        R1_hat=R1,
        R2_hat=R2,
        M_hat=M,
        Ll1_hat=est.Ll1_H if est.Ll1_H is not None else m.Ll1_H,
        Ll2_hat=est.Ll2_H if est.Ll2_H is not None else m.Ll2_H,
        R2_min=0.5 * R2 if lo is None else lo,
        R2_max=2.0 * R2 if hi is None else hi,
        G_CR=g.G_CR,
        gain_E=g.gain_E,
        gain_DE=g.gain_DE,
        inj_amp=(
            (inj.amplitude_A or 0.0) if inj.amplitude_pu is None else inj.amplitude_pu * psi / m.M_H
        ),
        inj_f1=f1,
        inj_f2=f2,
        inj_f3=f3,
        gate_band=g.gate_band_Hz,
        gate_speed_rpm=g.gate_speed_rpm,
        gate_iq_A=g.gate_iq_A,
        psi_rated=psi,
        I_rated=I_rated,
        speed_bandwidth_Hz=speed_bandwidth_Hz(sc),
        divergence_speed_rpm=divergence_speed_rpm(sc),
        sigma=m.sigma,
        T2_s=m.T2_s,
        v_max_V=sc.inverter.v_max_V,
        model_curve=sc.controller_model.uses_magnetising_curve,
        model_inverter_error=sc.controller_model.uses_inverter_error,
        current_limit_A=current_limit_A(sc),
        divergence_current_A=divergence_current_A(sc),
        sat_curve=sc.plant.saturation.curve(m),
        rotor_Rth=(
            rotor_thermal_resistance(sc) if comp.enabled and comp.thermal_model else math.nan
        ),
    )
    # the decision period holds whole periods of the injection frequency resolved above
    n_comp = decision_period_steps(comp, inj, sc.simulation.Ts_s, r)
    return dataclasses.replace(r, n_comp=n_comp)


def _rated_point_or_none(machine):
    """The machine's rated point, or None for a circuit without one (each caller then falls
    back on the synchronous speed): :func:`imdrive.config.rated.rated_point_or_none`."""
    from imdrive.config.rated import rated_point_or_none

    return rated_point_or_none(machine)


def _synchronous_rpm(machine) -> float:
    """The machine's synchronous speed at its rated frequency, rpm."""
    return 60.0 * machine.rated_frequency_Hz / machine.pole_pairs


def lost_control_rpm(sc) -> float:
    """The loss-of-control bound of scenario ``sc``, rpm: ``simulation.lost_control_rpm``, or
    by default twice the machine's rated slip speed, at least 1 % of its rated speed (a drive
    in control holds its speed within the slip error that even a 100 % R2_hat error causes).

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    float
        The bound, rpm (0: not checked).
    """
    given = sc.simulation.lost_control_rpm
    if given is not None:
        return given
    rp = _rated_point_or_none(sc.machine)
    if rp is None:  # a circuit without a rated point: the synchronous speed's 10 %
        return 0.1 * _synchronous_rpm(sc.machine)
    slip_rpm = rp.synchronous_speed_rpm - rp.speed_rpm
    return max(2.0 * slip_rpm, 0.01 * rp.speed_rpm)


def rated_slip_rpm(sc) -> float:
    """The machine's rated slip speed ``n_sync - n_rated``, rpm (mechanical): the unit of
    the per-unit speed errors (a 100 % R̂2 error shifts the speed by about this much at rated
    load). Without a rated point, 5 % of the synchronous speed.

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    float
        rpm.
    """
    rp = _rated_point_or_none(sc.machine)
    if rp is None:
        return 0.05 * _synchronous_rpm(sc.machine)
    return rp.synchronous_speed_rpm - rp.speed_rpm


#: the speed-error tolerance of a run's status: at least this, rpm ...
SPEED_TOLERANCE_MIN_RPM = 1.0
#: ... or this fraction of the rated speed, whichever is larger
SPEED_TOLERANCE_PU = 1e-3


def speed_tolerance_rpm(sc) -> float:
    """The speed-error tolerance of a run's status (:mod:`imdrive.run.status`), rpm: 1 rpm or
    0.1 % of the machine's rated speed, whichever is larger (1.72 rpm on Table IV).

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    float
        rpm.
    """
    rp = _rated_point_or_none(sc.machine)
    n_rated = _synchronous_rpm(sc.machine) if rp is None else rp.speed_rpm
    return max(SPEED_TOLERANCE_MIN_RPM, SPEED_TOLERANCE_PU * n_rated)


#: the controller's default current limit, per-unit of the rated peak current
CURRENT_LIMIT_PU = 1.5
#: the default current beyond which a run counts as diverged, per-unit of the rated peak current
DIVERGENCE_CURRENT_PU = 70.0


def rated_peak_current_A(machine) -> float:
    """The machine's rated current as a peak value, A: ``sqrt(2)`` times the nameplate's rms
    current (``machine.rated_current_rms_A``, or the circuit's at the rated point,
    :func:`~imdrive.config.rated.rated_point`). A circuit without a rated point falls back to
    ``sqrt(2) P / (sqrt(3) V)`` (``machine.rated_current_A``, efficiency and power factor 1).
    """
    from imdrive.config.machine import rated_point

    try:
        return rated_point(machine).current_peak_A
    except ConfigError:
        return machine.rated_current_A


def current_limit_A(sc) -> float:
    """The controller's stator current limit (peak), A: ``control.current_limit_A``, or by
    default :data:`CURRENT_LIMIT_PU` (1.5) times the rated peak current
    (:func:`rated_peak_current_A`): 17.2 A on Table IV, whose nameplate current is 8.1 A rms.

    The rule: an overload of 1.5 the rated current is what an industrial drive's inverter is
    commonly rated for over a short time (the "heavy duty" 150 % for 60 s), and it leaves the
    speed loop the rated torque plus a margin for the magnetising current at every library
    machine (their rated current is 1.7-3.6 times their magnetising current).
    """
    given = sc.control.current_limit_A
    return given if given is not None else CURRENT_LIMIT_PU * rated_peak_current_A(sc.machine)


#: the current sensors' ADC full scale on Table IV, A (:func:`adc_range_A`)
ADC_RANGE_TABLE_IV_A = 50.0


def adc_range_A(sc) -> float:
    """The current sensors' ADC full scale (±), A: ``sensor.adc_range_A``, ``sensor.adc_range_pu``
    times the rated peak current (:func:`rated_peak_current_A`), or by default Table IV's
    50 A scaled by the machine's rated peak current (:func:`table_iv_scaled`; 4.36 times it,
    2.9 times the default current limit on every machine; a fixed 50 A was below the rated
    peak current of the 500 hp, 2250 hp and 3.3 kV machines: 149, 650 and 503 A)."""
    sen = sc.sensor
    if sen.adc_range_A is not None:
        return sen.adc_range_A
    if sen.adc_range_pu is not None:
        return sen.adc_range_pu * rated_peak_current_A(sc.machine)
    return table_iv_scaled(ADC_RANGE_TABLE_IV_A, rated_peak_current_A, sc.machine)


def sign_band_A(sc) -> float:
    """The current band of the dead-time error's and compensation's smooth sign, A:
    ``inverter.sign_band_A``, ``inverter.sign_band_pu`` times the rated peak current, or by
    default Table IV's 0.2 A scaled by it (:func:`table_iv_scaled`): the current's ripple
    at the commutations, ``Vdc Ts / (sigma L1)``, is 0.2-0.7 of the rated peak current on
    every library machine at 10 kHz, where in amperes it spans 2.7-274 A."""
    inv = sc.inverter
    if inv.sign_band_A is not None:
        return inv.sign_band_A
    if inv.sign_band_pu is not None:
        return inv.sign_band_pu * rated_peak_current_A(sc.machine)
    return table_iv_scaled(0.2, rated_peak_current_A, sc.machine)


def divergence_current_A(sc) -> float:
    """The current beyond which a run counts as diverged, A: ``simulation.divergence_current_A``,
    or by default :data:`DIVERGENCE_CURRENT_PU` (70) times the rated peak current."""
    given = sc.simulation.divergence_current_A
    if given is not None:
        return given
    return DIVERGENCE_CURRENT_PU * rated_peak_current_A(sc.machine)


#: the speed bandwidth every machine gets at least, Hz (the paper's drive)
SPEED_BANDWIDTH_MIN_HZ = 5.0
#: the largest speed dip a rated-load step may cause, per-unit of the rated speed
SPEED_DIP_PU = 0.05


def speed_bandwidth_Hz(sc) -> float:
    """The speed loop's bandwidth of scenario ``sc``, Hz: ``control.speed_bandwidth_Hz``, or
    by default 5 Hz raised so that a rated-load step dips the speed by at most 5 % of the
    rated speed, so a drive at 10 % speed does not pass through zero (capped at a tenth of the
    current loop's bandwidth).

    With both poles of the speed PI at ``w_bw`` (:func:`imdrive.design.gains.default_speed_gains`)
    a torque step ``T`` dips the speed by about ``0.6 T / (J w_bw)`` (the peak of
    ``t exp(-w_bw t)`` scaled; measured 0.5-0.7 on the library), so the rule is
    ``w_bw >= 0.6 T_rated / (J 0.05 w_rated)``. Table IV keeps 5 Hz (1.9 Hz needed); the 2.2 kW
    Aalto machine (J = 0.015 kg m²) gets 12.3 Hz, where 5 Hz lost control at 10 % speed.

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    float
        Bandwidth, Hz.
    """
    given = sc.control.speed_bandwidth_Hz
    if given is not None:
        return given
    m = sc.machine
    rp = _rated_point_or_none(m)
    if rp is None:
        return SPEED_BANDWIDTH_MIN_HZ
    w_rated = rp.speed_rpm * math.pi / 30.0
    w_bw = 0.6 * rp.torque_Nm / (m.J_kgm2 * SPEED_DIP_PU * w_rated)
    need = w_bw / (2.0 * math.pi)
    return max(SPEED_BANDWIDTH_MIN_HZ, min(need, sc.control.current_bandwidth_Hz / 10.0))


def divergence_speed_rpm(sc) -> float:
    """The speed that stops a diverging run, rpm: ``simulation.divergence_speed_rpm``, or by
    default ``20000/1800`` times the machine's synchronous speed (20 000 rpm on the 1800 rpm
    Table IV machine, where the bound was first set; a 2-pole 400 Hz spindle would have hit a
    fixed 20 000 rpm in normal operation).

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    float
        The bound, rpm.
    """
    given = sc.simulation.divergence_speed_rpm
    if given is not None:
        return given
    m = sc.machine
    return 20000.0 * (60.0 * m.rated_frequency_Hz / m.pole_pairs) / 1800.0


def rated_rotor_loss_W(sc) -> float:
    """The machine's rotor copper losses at its rated point, W: the slip times the air-gap
    power, ``s T_rated w_sync`` (the rated point of :func:`imdrive.config.rated.rated_point`).

    Raises
    ------
    ConfigError
        The machine has no rated point (naming ``compensator.thermal_model``).
    """
    from imdrive.config.machine import rated_point

    try:
        rp = rated_point(sc.machine)
    except ConfigError as exc:
        raise ConfigError(
            "compensator.thermal_model", f"needs the machine's rated point ({exc})"
        ) from exc
    w_sync = rp.synchronous_speed_rpm * math.pi / 30.0
    return rp.slip * rp.torque_Nm * w_sync


def rotor_thermal_resistance(sc) -> float:
    """The rotor thermal model's thermal resistance to ambient, K/W: the temperature rise
    ``compensator.thermal_rise_K`` at the rated rotor losses (:func:`rated_rotor_loss_W`), so
    the same rise (an insulation class of IEC 60034-1) suits every machine."""
    return sc.compensator.thermal_rise_K / rated_rotor_loss_W(sc)


# the MRAS adaptation type by default lives in its own module (this one's size); imported
# here so the old import paths work
from imdrive.config.mras_type import (  # noqa: E402,F401
    MRAS_RAMP_LAG_MAX_PU,
    MRAS_TYPE2_ABOVE_PU,
    mras_ramp_lag_pu,
    mras_type2_for_field_weakening,
)
