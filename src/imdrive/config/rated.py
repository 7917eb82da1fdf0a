"""The machine's rated operating point and the nameplate-against-circuit checks.

:func:`rated_point` completes a nameplate from the T-equivalent circuit at rated voltage and
frequency (speed, torque, current, power factor, efficiency, magnetising current, breakdown
torque), saying how each value was obtained; :func:`check_nameplate` refuses contradictions
between the nameplate and the circuit and warns about oddities. The steady state is the
T-circuit of :mod:`imdrive.analysis.circuit` (the same equations, written with Python's complex
numbers so that this layer needs no numpy). :mod:`imdrive.config.machine` serves these names
too.
"""

from __future__ import annotations

import cmath
import functools
import math
import warnings
from dataclasses import asdict, dataclass, fields
from typing import Any

from imdrive.errors import ConfigError, ConfigWarning

#: A machine's circuit and nameplate: a :class:`~imdrive.config.machine.MachineParams`, or
#: anything with its fields (that module imports this one, so this one does not import it).
MachineParams = Any

#: Above this rated slip a nameplate is suspicious (:class:`~imdrive.errors.ConfigWarning`).
SLIP_WARN = 0.10
#: Outside this range a rated power factor is suspicious.
POWER_FACTOR_WARN = (0.5, 0.95)


# ------------------------------------------------------------------------------------------
# the T-equivalent circuit's steady state (the equations of imdrive.analysis.circuit)


def _steady(m: MachineParams, V_ll: float, f: float, s: float) -> dict:
    """Peak-value phasors and powers of the T-circuit at slip ``s`` (see
    :func:`imdrive.analysis.circuit.equivalent_circuit`, whose equations these are)."""
    w_e = 2.0 * math.pi * f
    X_M = w_e * m.M_H
    rotor_den = m.R2_ohm + 1j * s * w_e * m.L2_H
    Z = m.R1_ohm + 1j * w_e * m.L1_H + s * X_M**2 / rotor_den
    V1 = math.sqrt(2.0 / 3.0) * V_ll
    I1 = V1 / Z
    I2 = -1j * s * X_M * I1 / rotor_den
    torque = 1.5 * m.pole_pairs * s * X_M**2 * m.R2_ohm * abs(I1) ** 2 / (w_e * abs(rotor_den) ** 2)
    return {
        "I1": I1,
        "Im": I1 + I2,
        "psi_r": m.M_H * I1 + m.L2_H * I2,
        "torque": torque,
        "P_in": 1.5 * (V1 * I1.conjugate()).real,
        "P_mech": torque * (1.0 - s) * w_e / m.pole_pairs,
        "pf": math.cos(cmath.phase(I1)),
    }


def _breakdown(m: MachineParams, V_ll: float, f: float) -> tuple[float, float]:
    """Breakdown slip and torque, closed form through the stator's Thevenin equivalent
    (:func:`imdrive.analysis.circuit.breakdown_thevenin`, which derives it)."""
    w_e = 2.0 * math.pi * f
    X_l1, X_l2, X_M = w_e * m.Ll1_H, w_e * m.Ll2_H, w_e * m.M_H
    den = m.R1_ohm + 1j * (X_l1 + X_M)
    V_th = math.sqrt(2.0 / 3.0) * V_ll * 1j * X_M / den
    Z_th = 1j * X_M * (m.R1_ohm + 1j * X_l1) / den
    root = math.hypot(Z_th.real, Z_th.imag + X_l2)
    return m.R2_ohm / root, 1.5 * m.pole_pairs * abs(V_th) ** 2 / (2.0 * w_e * (Z_th.real + root))


def _no_load_current_rms(m: MachineParams) -> float:
    """Line current at synchronous speed (``s = 0``), rated voltage and frequency, rms, A."""
    w_e = 2.0 * math.pi * m.rated_frequency_Hz
    return m.rated_voltage_V / math.sqrt(3.0) / abs(m.R1_ohm + 1j * w_e * m.L1_H)


def _bisect(g, lo: float, hi: float) -> float:
    """The root of the increasing function ``g`` in ``[lo, hi]`` (``g(lo) < 0 < g(hi)``)."""
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if g(mid) < 0.0:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-15 * hi:
            break
    return 0.5 * (lo + hi)


def _slip_at_torque(m: MachineParams, torque: float, s_bd: float) -> float:
    """Slip on the stable branch ``0 < s < s_bd`` where the circuit's torque is ``torque``."""
    V, f = m.rated_voltage_V, m.rated_frequency_Hz
    return _bisect(lambda s: _steady(m, V, f, s)["torque"] - torque, 0.0, s_bd)


def _max_mech_power(m: MachineParams, s_bd: float) -> tuple[float, float]:
    """Slip and value of the maximum of ``P_mech(s)`` on ``0 < s < s_bd`` (golden section;
    ``P_mech = T (1 - s) w_s`` is unimodal there)."""
    V, f = m.rated_voltage_V, m.rated_frequency_Hz
    g = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = 0.0, s_bd
    for _ in range(100):
        c, d = b - g * (b - a), a + g * (b - a)
        if _steady(m, V, f, c)["P_mech"] > _steady(m, V, f, d)["P_mech"]:
            b = d
        else:
            a = c
    s = 0.5 * (a + b)
    return s, _steady(m, V, f, s)["P_mech"]


# ------------------------------------------------------------------------------------------
# the rated operating point


@dataclass(frozen=True)
class RatedPoint:
    """The rated operating point of a machine: its nameplate, completed from the circuit.

    Built by :func:`rated_point`. Currents are line (phase, star-equivalent) rms values as on a
    nameplate unless the name says ``peak``; fluxes are space-vector magnitudes (the peak of a
    phase flux linkage, the package's amplitude-invariant convention).

    Attributes
    ----------
    voltage_V, frequency_Hz : float
        Rated line-to-line rms voltage, V, and frequency, Hz.
    w_e_rad_s : float
        Base electrical angular frequency ``2 pi f``, rad/s.
    power_W : float
        Rated shaft power, W.
    synchronous_speed_rpm, speed_rpm : float
        ``60 f / n_p`` and the rated speed, rpm.
    slip : float
        Rated slip ``1 - speed / synchronous speed``, dimensionless.
    torque_Nm : float
        Rated shaft torque, N m.
    current_rms_A, current_peak_A : float
        Rated line current, A (rms, and its peak ``sqrt 2`` times).
    power_factor, efficiency : float
        At rated load, dimensionless.
    magnetising_current_rms_A : float
        ``|I1 + I2|`` of the circuit at rated torque, rms, A.
    psi_r_Wb : float
        Rotor flux of the circuit at rated torque, Wb.
    no_load_current_rms_A : float
        Line current of the circuit at synchronous speed, rated voltage, rms, A.
    breakdown_torque_Nm, breakdown_slip : float
        Maximum motoring torque of the circuit at rated voltage and frequency, N m, and its
        slip, dimensionless.
    circuit_speed_rpm, circuit_current_rms_A, circuit_power_factor : float
        The circuit's own speed (rpm), current (A rms) and power factor (dimensionless) loaded
        to ``torque_Nm``.
    sources : dict of str to str
        How each nameplate quantity was obtained (``"nameplate"`` or the formula).
    """

    voltage_V: float
    frequency_Hz: float
    w_e_rad_s: float
    power_W: float
    synchronous_speed_rpm: float
    speed_rpm: float
    slip: float
    torque_Nm: float
    current_rms_A: float
    current_peak_A: float
    power_factor: float
    efficiency: float
    magnetising_current_rms_A: float
    psi_r_Wb: float
    no_load_current_rms_A: float
    breakdown_torque_Nm: float
    breakdown_slip: float
    circuit_speed_rpm: float
    circuit_current_rms_A: float
    circuit_power_factor: float
    sources: dict

    def to_dict(self) -> dict[str, float]:
        """The numbers (``sources`` left out), for ``summary.json`` ``machine_rated``.

        Returns
        -------
        dict of str to float
            Attribute name -> value, units in the names.
        """
        return {k: float(v) for k, v in asdict(self).items() if k != "sources"}


def _rated_point_uncached(m: MachineParams) -> RatedPoint:
    """The rated operating point: the nameplate where given, derived where not.


    Parameters
    ----------
    m : MachineParams
        The machine (circuit and nameplate).

    Returns
    -------
    RatedPoint
        Rated voltage, frequency, speed, slip, torque, current, power factor, efficiency,
        magnetising current, rotor flux, breakdown torque; ``sources`` says where each came
        from.

    Raises
    ------
    ConfigError
        ``machine.rated_power_W`` when neither speed nor torque is given and the circuit
        cannot deliver the rated power at rated voltage and frequency; the torque's field when
        the rated torque is not below the breakdown torque.

    Notes
    -----
    With ``P`` the rated power, ``V`` the line voltage, ``w_m`` the mechanical speed:

    * speed: the nameplate's; else ``w_m = P / T_rated`` when the torque is given; else the
      circuit's speed on its stable branch where ``P_mech(s) = T_e(s) (1 - s) w_e / n_p = P``
      (the smaller of the two slips; friction and iron losses are not in the circuit);
    * torque: the nameplate's; else ``T = P / w_m = P / (2 pi n / 60)``;
    * current: the nameplate's; else ``I = P / (sqrt 3 V eta cos phi)`` when efficiency and
      power factor are given; else the circuit's ``|I1|`` at rated torque;
    * power factor, efficiency: the nameplate's; else the circuit's at rated torque
      (``P_mech / P_in``, copper losses only, so above a real machine's);
    * magnetising current ``|I1 + I2|``, rotor flux ``|M I1 + L2 I2|``: the circuit's at the
      slip where its torque equals the rated torque (the circuit's rated point, which differs
      from the nameplate's speed where nameplate and circuit disagree).

    The circuit is :func:`imdrive.analysis.circuit.equivalent_circuit`'s, at rated voltage and
    frequency.
    """
    V, f, P = m.rated_voltage_V, m.rated_frequency_Hz, m.rated_power_W
    n_sync = 60.0 * f / m.pole_pairs
    s_bd, T_bd = _breakdown(m, V, f)
    sources = {}
    if m.rated_speed_rpm is not None:
        speed, sources["speed_rpm"] = m.rated_speed_rpm, "nameplate"
    elif m.rated_torque_Nm is not None:  # checked as a given speed is
        speed = _derived_speed_rule(m, n_sync, "machine.rated_torque_Nm")
        sources["speed_rpm"] = "P / T_rated"
    else:
        s_p, P_max = _max_mech_power(m, s_bd)
        if not P < P_max:
            raise ConfigError(
                "machine.rated_power_W",
                f"{P:.6g} W is more than the circuit delivers at rated voltage and frequency "
                f"({P_max:.6g} W); give rated_speed_rpm or check the circuit",
            )
        s = _bisect(lambda s: _steady(m, V, f, s)["P_mech"] - P, 0.0, s_p)
        speed, sources["speed_rpm"] = (1.0 - s) * n_sync, "circuit: P_mech(s) = P"
    if m.rated_torque_Nm is not None:
        torque, sources["torque_Nm"] = m.rated_torque_Nm, "nameplate"
    else:
        torque, sources["torque_Nm"] = P / (speed * math.pi / 30.0), "P / (2 pi n / 60)"
    if not torque < T_bd:
        field = "rated_torque_Nm" if m.rated_torque_Nm is not None else "rated_speed_rpm"
        raise ConfigError(
            f"machine.{field}",
            f"rated torque {torque:.4g} N m is not below the circuit's breakdown torque "
            f"{T_bd:.4g} N m at rated voltage and frequency",
        )
    s_c = _slip_at_torque(m, torque, s_bd)
    op = _steady(m, V, f, s_c)
    I_circ = abs(op["I1"]) / math.sqrt(2.0)
    pf, sources["power_factor"] = (
        (m.rated_power_factor, "nameplate")
        if m.rated_power_factor is not None
        else (op["pf"], "circuit at rated torque")
    )
    eta, sources["efficiency"] = (
        (m.rated_efficiency, "nameplate")
        if m.rated_efficiency is not None
        else (op["P_mech"] / op["P_in"], "circuit at rated torque (copper losses only)")
    )
    if m.rated_current_rms_A is not None:
        current, sources["current_rms_A"] = m.rated_current_rms_A, "nameplate"
    elif m.rated_efficiency is not None and m.rated_power_factor is not None:
        current = P / (math.sqrt(3.0) * V * eta * pf)
        sources["current_rms_A"] = "P / (sqrt(3) V eta cos phi)"
    else:
        current, sources["current_rms_A"] = I_circ, "circuit at rated torque"
    return RatedPoint(
        voltage_V=V,
        frequency_Hz=f,
        w_e_rad_s=2.0 * math.pi * f,
        power_W=P,
        synchronous_speed_rpm=n_sync,
        speed_rpm=speed,
        slip=1.0 - speed / n_sync,
        torque_Nm=torque,
        current_rms_A=current,
        current_peak_A=math.sqrt(2.0) * current,
        power_factor=pf,
        efficiency=eta,
        magnetising_current_rms_A=abs(op["Im"]) / math.sqrt(2.0),
        psi_r_Wb=abs(op["psi_r"]),
        no_load_current_rms_A=_no_load_current_rms(m),
        breakdown_torque_Nm=T_bd,
        breakdown_slip=s_bd,
        circuit_speed_rpm=(1.0 - s_c) * n_sync,
        circuit_current_rms_A=I_circ,
        circuit_power_factor=op["pf"],
        sources=sources,
    )


def _derived_speed_rule(m: MachineParams, n_sync: float, field: str) -> float:
    """The rated speed ``P / T_rated`` derived from a given rated torque, refused (naming
    ``field``) unless it is above 0 and below the synchronous speed, as a given one is: a
    rated torque below ``P / w_sync`` made a "rated speed" above synchronous, a negative
    slip, and NaN in every per-unit-of-slip figure."""
    speed = m.rated_power_W / m.rated_torque_Nm * 30.0 / math.pi
    if not 0.0 < speed < n_sync:
        T_min = m.rated_power_W / (n_sync * math.pi / 30.0)
        raise ConfigError(
            field,
            f"{m.rated_torque_Nm:g} N m gives a rated speed rated_power_W / rated_torque_Nm = "
            f"{speed:.6g} rpm, not below the synchronous speed {n_sync:.6g} rpm: the rated "
            f"torque must be above {T_min:.6g} N m (or give rated_speed_rpm)",
        )
    return speed


def check_nameplate(m: MachineParams) -> None:
    """Refuse a nameplate that contradicts the circuit; warn of a suspicious one.

    Parameters
    ----------
    m : MachineParams
        The machine.

    Raises
    ------
    ConfigError
        (Field names relative to ``[machine]``: the settings class prefixes them.) A rated
        speed not below synchronous speed, given or derived from a given rated torque
        (``P / T_rated``); a given rated torque (or ``P / w_m`` of a
        given rated speed) not below the circuit's breakdown torque at rated voltage and
        frequency; a given rated current (or ``P / (sqrt 3 V eta cos phi)`` of given
        efficiency and power factor) not above the circuit's no-load current. The message
        names the fields.

    Warns
    -----
    ConfigWarning
        Rated slip above 10 %; rated power factor outside 0.5-0.95; a given torque and speed
        whose product is not the rated power within 5 %; a given current, efficiency and power
        factor that do not give the rated power within 10 %; a rated power the circuit cannot
        deliver (when neither speed nor torque is given).
    """
    V, f, P = m.rated_voltage_V, m.rated_frequency_Hz, m.rated_power_W
    n_sync = 60.0 * f / m.pole_pairs
    if m.rated_speed_rpm is not None and not m.rated_speed_rpm < n_sync:
        raise ConfigError(
            "rated_speed_rpm",
            f"{m.rated_speed_rpm:g} rpm must be below the synchronous speed "
            f"60 rated_frequency_Hz / pole_pairs = {n_sync:.6g} rpm",
        )
    if m.rated_speed_rpm is None and m.rated_torque_Nm is not None:
        _derived_speed_rule(m, n_sync, "rated_torque_Nm")
    _, T_bd = _breakdown(m, V, f)
    circuit = (
        "(the circuit R1_ohm, R2_ohm, Ll1_H, Ll2_H, M_H at rated_voltage_V, rated_frequency_Hz)"
    )
    if m.rated_torque_Nm is not None:
        torque, field = m.rated_torque_Nm, "rated_torque_Nm"
    elif m.rated_speed_rpm is not None:
        torque = P / (m.rated_speed_rpm * math.pi / 30.0)
        field = "rated_speed_rpm"
    else:
        torque = field = None
    if torque is not None and not torque < T_bd:
        raise ConfigError(
            field,
            f"rated torque {torque:.4g} N m must be below the breakdown torque {T_bd:.4g} N m "
            f"{circuit}",
        )
    I_0 = _no_load_current_rms(m)
    if m.rated_current_rms_A is not None:
        current, field = m.rated_current_rms_A, "rated_current_rms_A"
    elif m.rated_efficiency is not None and m.rated_power_factor is not None:
        current = P / (math.sqrt(3.0) * V * m.rated_efficiency * m.rated_power_factor)
        field = "rated_efficiency, rated_power_factor"
    else:
        current = None
    if current is not None and not current > I_0:
        raise ConfigError(
            field,
            f"rated current {current:.4g} A must be above the no-load (magnetising) current "
            f"{I_0:.4g} A {circuit}",
        )
    if m.rated_torque_Nm is not None and m.rated_speed_rpm is not None:
        P_check = m.rated_torque_Nm * m.rated_speed_rpm * math.pi / 30.0
        if abs(P_check / P - 1.0) > 0.05:
            _warn(
                "machine.rated_torque_Nm",
                f"rated_torque_Nm x rated_speed_rpm gives {P_check:.5g} W, not "
                f"rated_power_W = {P:.5g} W (more than 5 % apart)",
            )
    if None not in (m.rated_current_rms_A, m.rated_efficiency, m.rated_power_factor):
        P_check = math.sqrt(3.0) * V * m.rated_current_rms_A * m.rated_efficiency
        P_check *= m.rated_power_factor
        if abs(P_check / P - 1.0) > 0.10:
            _warn(
                "machine.rated_current_rms_A",
                f"sqrt(3) V I eta cos phi gives {P_check:.5g} W, not rated_power_W = {P:.5g} W "
                "(more than 10 % apart)",
            )
    try:
        rp = rated_point(m)
    except ConfigError as exc:
        _warn(exc.field, exc.rule)
        return
    if rp.slip > SLIP_WARN:
        _warn(
            "machine.rated_speed_rpm",
            f"rated slip {100 * rp.slip:.3g} % ({rp.sources['speed_rpm']}) is above "
            f"{100 * SLIP_WARN:g} %: check the speed and the circuit",
        )
    lo, hi = POWER_FACTOR_WARN
    if not lo <= rp.power_factor <= hi:
        _warn(
            "machine.rated_power_factor",
            f"rated power factor {rp.power_factor:.3g} ({rp.sources['power_factor']}) is "
            f"outside {lo:g}-{hi:g}",
        )


@dataclass(frozen=True)
class _CircuitAndPlate:
    """The fields :func:`check_nameplate` reads (hashable: the key of its cache)."""

    R1_ohm: float
    R2_ohm: float
    Ll1_H: float
    Ll2_H: float
    M_H: float
    pole_pairs: int
    rated_power_W: float
    rated_voltage_V: float
    rated_frequency_Hz: float
    rated_speed_rpm: float | None
    rated_torque_Nm: float | None
    rated_current_rms_A: float | None
    rated_power_factor: float | None
    rated_efficiency: float | None

    @classmethod
    def of(cls, m) -> _CircuitAndPlate:
        return cls(**{f.name: getattr(m, f.name) for f in fields(cls)})

    @property
    def L1_H(self) -> float:
        return self.Ll1_H + self.M_H

    @property
    def L2_H(self) -> float:
        return self.Ll2_H + self.M_H


@functools.lru_cache(maxsize=1024)
def _nameplate_findings(key: _CircuitAndPlate) -> tuple[tuple[str, str], ...]:
    """:func:`check_nameplate`'s warnings as ``(field, rule)`` pairs, computed once per
    distinct circuit and nameplate (its errors are raised, and not cached)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConfigWarning)
        check_nameplate(key)  # it reads only these fields
    return tuple(
        (w.message.field, w.message.rule) for w in caught if isinstance(w.message, ConfigWarning)
    )


def nameplate_findings(m: MachineParams) -> tuple[tuple[str, str], ...]:
    """The nameplate-against-circuit warnings of ``m`` as ``(field, rule)`` pairs.

    Parameters
    ----------
    m : MachineParams
        The machine.

    Returns
    -------
    tuple of (str, str)
        What :func:`check_nameplate` warns about (computed once per distinct circuit and
        nameplate); its contradictions are raised as :class:`~imdrive.errors.ConfigError`.
    """
    return _nameplate_findings(_CircuitAndPlate.of(m))


def _warn(field: str, rule: str) -> None:
    warnings.warn(ConfigWarning(field, rule), stacklevel=2)


def rated_point_comment(m: MachineParams) -> str:
    """The derived rated point as TOML comment lines (for ``imdrive show``).

    Parameters
    ----------
    m : MachineParams
        The machine.

    Returns
    -------
    str
        ``# name = value  (how it was obtained)`` lines, or one line saying why there is none.
    """
    try:
        rp = rated_point(m)
    except ConfigError as exc:
        return f"# no rated point: {exc}\n"
    lines = ["# rated point (imdrive.config.machine.rated_point; not keys of the file):"]
    for k, v in rp.to_dict().items():
        how = rp.sources.get(k, "")
        lines.append(f"#   {k} = {v:.6g}" + (f"  ({how})" if how else ""))
    return "\n".join(lines) + "\n"


@functools.lru_cache(maxsize=256)
def _rated_point_cached(m: MachineParams) -> RatedPoint:
    return _rated_point_uncached(m)


def rated_point(m: MachineParams) -> RatedPoint:
    """The rated operating point: the nameplate where given, derived where not (computed once
    per distinct machine; see :func:`_rated_point_uncached` for the method).

    Parameters
    ----------
    m : MachineParams
        The machine (circuit and nameplate).

    Returns
    -------
    RatedPoint
        As :func:`_rated_point_uncached`; a ``ConfigError`` it raises is raised again each
        time (errors are not cached).
    """
    try:
        return _rated_point_cached(m)
    except TypeError:  # an unhashable machine (never for MachineParams): no cache
        return _rated_point_uncached(m)


def rated_point_dict(m: MachineParams) -> dict | None:
    """The machine's rated point as numbers (``summary.json`` ``machine_rated``), or ``None``
    when its circuit has none (it cannot deliver the rated power).

    Parameters
    ----------
    m : MachineParams
        The machine.

    Returns
    -------
    dict or None
        :meth:`RatedPoint.to_dict`.
    """
    try:
        return rated_point(m).to_dict()
    except ConfigError:
        return None


def rated_point_or_none(m: MachineParams) -> RatedPoint | None:
    """:func:`rated_point`, or None for a circuit without one (its ``ConfigError``): callers
    whose per-unit rule then does not apply, or falls back on the synchronous speed.

    Parameters
    ----------
    m : MachineParams
        The machine.

    Returns
    -------
    RatedPoint or None
    """
    try:
        return rated_point(m)
    except ConfigError:
        return None
