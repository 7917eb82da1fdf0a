"""The steady state a field-oriented drive scenario settles at: the flux it runs at, the
speed error it holds with a detuned R2_hat, and its stator frequency (the machine envelope
and the zero-frequency study, :mod:`imdrive.studies.machines`, judge runs by them; they lived
there until 2026-11-30 and are still importable from it).
"""

from __future__ import annotations

from imdrive.analysis import detuning_speed_error_rpm, field_weakened_flux_Wb
from imdrive.analysis.foc import foc_operating_point
from imdrive.config.defaults import in_effect


def law_flux_Wb(sc, speed_rpm: float, load_Nm: float, R2_ratio: float) -> float:
    """The rotor flux the sensorless drive ``sc`` settles at, Wb: its reference (the machine's
    rated flux), or with ``control.field_weakening`` the flux at which the steady state's
    stator voltage is ``field_weakening_voltage`` of ``Vdc/sqrt 3``
    (:func:`imdrive.analysis.field_weakened_flux_Wb`)."""
    psi = sc.machine.rated_flux_Wb
    if not in_effect(sc, "control.field_weakening"):
        return psi
    hold = sc.control.field_weakening_voltage * sc.inverter.v_max_V
    return field_weakened_flux_Wb(
        sc.machine,
        speed_rpm,
        load_Nm,
        R2_ratio,
        hold,
        psi,
        sc.control.field_weakening_min,
        no_load_bound=sc.control.field_weakening_bound,
    )


def detuning_law_rpm(sc, speed_rpm: float, load_Nm: float, R2_ratio: float) -> float:
    """The speed error the sensorless drive ``sc`` holds in steady state, rpm.

    The MRAS detuning law ``slip (R2_hat/R2 - 1)`` (:func:`imdrive.analysis.foc`) at the flux
    the drive runs (:func:`law_flux_Wb`). The slip grows as ``1/psi_r^2``: at rated speed and
    the rated torque the field weakening settles at 0.80-0.88 of the rated flux motoring,
    0.89-0.93 regenerating on the three large machines, and the law is up to 1.56 times the
    rated-flux one (the Aalto machine, motoring).
    """
    psi = law_flux_Wb(sc, speed_rpm, load_Nm, R2_ratio)
    return float(detuning_speed_error_rpm(sc.machine, speed_rpm, load_Nm, R2_ratio, psi))


def stator_frequency_Hz(sc, speed_rpm: float, load_Nm: float, R2_ratio: float) -> float:
    """The stator frequency of the drive's steady state with ``R2_hat = R2_ratio R2``, Hz.

    :func:`imdrive.analysis.foc_operating_point` (sensorless: the speed estimate at the
    reference) at the flux the drive runs (:func:`law_flux_Wb`). Regenerating at low speed it
    is ``n_p w_m - w_sl``: the slip's magnitude grows with ``R2_hat`` and with the machine's
    rated slip, and at 5 % of the rated speed regenerating the rated torque it reaches zero on
    a machine whose rated slip is about 5 % -- the line on which the speed is not observable
    from the fundamental-frequency voltages and currents (Holtz, "Sensorless control of
    induction motor drives", Proc. IEEE 90(8), 2002).
    """
    psi = law_flux_Wb(sc, speed_rpm, load_Nm, R2_ratio)
    return float(foc_operating_point(sc.machine, speed_rpm, load_Nm, R2_ratio, psi).f_Hz)
