"""Whether the drive runs its field weakening: ``control.field_weakening`` as given, or by
default when the scenario's speed reference takes the drive to the inverter's voltage.

Every consumer of the setting (the controller's voltage feedback, the MRAS's flux
normalisation, the injection's headroom, the type-2 MRAS default, the machine envelope's
detuning law) asks :func:`field_weakening_on`, so the default is decided once, on the
scenario as it runs (a sweep's speed axis, a ``--set``), never on a preset's speed.
"""

from __future__ import annotations

import math

from imdrive.config.rated import rated_point_or_none as _rated_point_or_none


def field_weakening_on(sc) -> bool:
    """``control.field_weakening`` if set, else :func:`field_weakening_needed`.

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    bool
    """
    given = sc.control.field_weakening
    return bool(given) if given is not None else field_weakening_needed(sc)


def rated_torque_voltage_V(sc, speed_rpm: float) -> float:
    """Peak phase voltage the field-oriented steady state needs at ``speed_rpm`` with the
    controller's flux reference and the machine's rated torque, motoring, V.

    In the rotor-flux frame at steady state (``psi_r = M i_d``, ``psi_s = L1 i_d + j sigma L1
    i_q``; e.g. Novotny and Lipo, *Vector Control and Dynamics of AC Drives*, Oxford 1996,
    ch. 5)::

        i_d = psi / M,    i_q = T L2 / (1.5 n_p M psi),    w_e = n_p w_m + R2 M i_q / (L2 psi)
        v_d = R1 i_d - w_e sigma L1 i_q,    v_q = R1 i_q + w_e L1 i_d

    Motoring at the rated torque is the case that needs the most voltage at a given speed
    (regenerating, the resistive and leakage drops turn against the back-emf).

    Parameters
    ----------
    sc : Scenario
        The scenario (its machine, ``control.flux_ref_Wb``: its largest value).
    speed_rpm : float
        Mechanical speed, rpm (its magnitude is used).

    Returns
    -------
    float
        ``|v_s|``, V; nan without a rated point.
    """
    m = sc.machine
    rp = _rated_point_or_none(m)
    if rp is None:
        return math.nan
    psi = m.rated_flux_Wb
    if sc.control.flux_ref_Wb is not None:  # a profile: its largest value
        psi = sc.control.flux_ref_Wb.peak
    L1, L2, M = m.M_H + m.Ll1_H, m.M_H + m.Ll2_H, m.M_H
    sigma_L1 = L1 - M * M / L2
    i_d = psi / M
    i_q = rp.torque_Nm * L2 / (1.5 * m.pole_pairs * M * psi)
    w_e = m.pole_pairs * abs(speed_rpm) * math.pi / 30.0 + m.R2_ohm * M * i_q / (L2 * psi)
    v_d = m.R1_ohm * i_d - w_e * sigma_L1 * i_q
    v_q = m.R1_ohm * i_q + w_e * L1 * i_d
    return math.hypot(v_d, v_q)


def field_weakening_needed(sc) -> bool:
    """Whether the scenario's speed reference reaches the speed where the field weakening's
    voltage feedback would act at the rated torque: the steady state there
    (:func:`rated_torque_voltage_V`, rated flux, motoring) needs more than
    ``control.field_weakening_voltage`` of the inverter's limit ``Vdc/sqrt 3``.

    With the DC link at ``sqrt 2`` times the rated voltage (the default) there is no voltage
    margin at the rated speed: the steady state at rated flux and torque needs 1.01-1.06 of
    the limit on the library's machines (0.97-1.0 regenerating on the large ones). Without
    the field weakening the current loops then sit at the limit, a step of regenerating
    torque runs the q current past its reference and control is lost (Krause 500 hp, the
    3.3 kV machine), and a motoring drive holds its speed on a weaker, misoriented flux. The
    rule switches the feedback on from 0.84-0.88 of the rated speed on the library's machines;
    drives that stay below (the paper's 1000 rpm presets on Table IV, 0.58 of its rated
    speed) keep it off, as before.

    Parameters
    ----------
    sc : Scenario
        The scenario (``drive.mode``, ``control.speed_ref_rpm`` or ``_pu``, ``inverter.v_max_V``).

    Returns
    -------
    bool
        False for a drive that is not field oriented or a machine without a rated point.
    """
    if sc.drive.mode != "vector":
        return False
    from imdrive.config.profile_units import stated_speed_ref_rpm

    needed = rated_torque_voltage_V(sc, stated_speed_ref_rpm(sc).peak)
    v_max = sc.inverter.v_max_V
    return bool(needed > sc.control.field_weakening_voltage * v_max)
