"""The fuzzy compensator's machine-dependent settings, resolved on the scenario's machine.

Each is given in SI (``compensator.G_CR_ohm``), in per-unit of the machine (its twin
``G_CR_pu``, which wins when set), or left unset: then the paper's (or our first release's)
number on the Table IV machine scaled by the machine's base quantity
(:func:`imdrive.config.table_iv.table_iv_scaled`, exactly the old number on Table IV):

======================  ===========  ==============================================
setting                 Table IV     scaled by
======================  ===========  ==============================================
``G_CR_ohm``            0.001 ohm    the machine's R2 (the step stays 0.12 % of R2)
``gain_E_per_Wb``       1e6 /Wb      ``1 / psi_rated``: e_d0 is a flux, so the
(E and DE)                           quantiser's thresholds stay the same share of it
``gate_speed_rpm``      1 rpm        the rated slip speed (79 rpm on Table IV)
``gate_iq_A``           0.3 A        the rated current ``machine.rated_current_A``
``gate_band_Hz``        1.5 Hz       the first injection frequency in use (0.75 of it)
``injection.            2 Hz         the machine's rotor corner ``R2/(2 pi L2)``,
frequency_Hz``                       to whole control periods
======================  ===========  ==============================================

The paper's presets state their numbers (paper §4: its micro-weber thresholds, 1e6 /Wb,
and 0.001 ohm); with their ``[machine]`` replaced, :func:`imdrive.config.pairs.set_layer`
warns that those stay as given.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from imdrive.config.table_iv import table_iv_scaled

#: the unset defaults on the Table IV machine (module docstring)
TABLE_IV = {
    "G_CR_ohm": 0.001,
    "gain_E_per_Wb": 1e6,
    "gate_speed_rpm": 1.0,
    "gate_iq_A": 0.3,
}
#: the injection's frequency on Table IV, Hz (1.1 times its rotor corner R2/(2 pi L2), 1.82 Hz)
INJECTION_TABLE_IV_HZ = 2.0
#: the gate's band around the injection frequency, per-unit of it, when neither
#: ``gate_band_Hz`` nor ``gate_band_pu`` is set (1.5 Hz of the 2 Hz injection on Table IV):
#: above half, so the schedule's harmonics f, 2f, 3f overlap and a stator frequency midway
#: between two of them takes the third instead of switching at every decision (0.5 was the
#: default of the two-frequency schedule; every injection preset set 0.75)
GATE_BAND_PU = 0.75


class CompensatorGains(NamedTuple):
    """The compensator's resolved machine-dependent settings (SI)."""

    G_CR: float  #: change of R̂2 per output level and period, ohm
    gain_E: float  #: scaling of e_d0 before the quantiser, 1/Wb
    gain_DE: float  #: scaling of e_d0's change per period, 1/Wb
    gate_speed_rpm: float  #: the gate's speed threshold, rpm
    gate_iq_A: float  #: the gate's load-transient threshold, A
    gate_band_Hz: float  #: the gate's band around the injection frequency, Hz


def _rated_slip_rpm(machine) -> float:
    """The rated slip speed, rpm (the base of ``gate_speed_pu``: a machine without a rated
    point raises its ``ConfigError``)."""
    from imdrive.config.rated import rated_point

    rp = rated_point(machine)
    return rp.synchronous_speed_rpm - rp.speed_rpm


def _gate_speed_base(machine) -> float:
    """The base the unset gate speed scales by: the rated slip speed, or for a circuit without
    a rated point (it cannot deliver its rated power) its synchronous speed over Table IV's
    ratio of the two."""
    from imdrive.config.rated import rated_point_or_none

    if rated_point_or_none(machine) is not None:
        return _rated_slip_rpm(machine)
    from imdrive.config.machine import machine_preset

    t4 = machine_preset("paper-table-iv")
    return _synchronous_rpm(machine) * _rated_slip_rpm(t4) / _synchronous_rpm(t4)


def _synchronous_rpm(machine) -> float:
    return 60.0 * machine.rated_frequency_Hz / machine.pole_pairs


def _inverse_rated_flux(machine) -> float:
    return 1.0 / machine.rated_flux_Wb


def _pick(pu, pu_base: float, absolute, table_iv: float, base, machine) -> float:
    """``pu x pu_base`` when the per-unit twin is set, else the absolute value, else Table IV's
    number scaled by ``base`` (:func:`~imdrive.config.table_iv.table_iv_scaled`)."""
    if pu is not None:
        return pu * pu_base
    if absolute is not None:
        return absolute
    return table_iv_scaled(table_iv, base, machine)


def compensator_gains(comp, machine, R2_hat: float, f_injection_Hz: float) -> CompensatorGains:
    """Resolve the compensator's machine-dependent settings (module docstring).

    Parameters
    ----------
    comp : CompensatorSettings
        ``[compensator]``.
    machine : MachineParams
        The scenario's machine.
    R2_hat : float
        The controller's starting R̂2, ohm (the base of ``G_CR_pu``).
    f_injection_Hz : float
        The first injection frequency in use at the start, Hz (the base of the gate's band).

    Returns
    -------
    CompensatorGains
    """
    psi = machine.rated_flux_Wb
    gain_E = _pick(
        comp.gain_E_pu,
        1.0 / psi,
        comp.gain_E_per_Wb,
        TABLE_IV["gain_E_per_Wb"],
        _inverse_rated_flux,
        machine,
    )
    if comp.gate_band_pu is not None:
        band = comp.gate_band_pu * f_injection_Hz
    elif comp.gate_band_Hz is not None:
        band = comp.gate_band_Hz
    else:
        band = GATE_BAND_PU * f_injection_Hz
    return CompensatorGains(
        G_CR=_pick(
            comp.G_CR_pu,
            R2_hat,
            comp.G_CR_ohm,
            TABLE_IV["G_CR_ohm"],
            lambda m: m.R2_ohm,
            machine,
        ),
        gain_E=gain_E,
        gain_DE=gain_E,  # DE is scaled as E (the paper's Tables I and II: one set of thresholds)
        gate_speed_rpm=_pick(
            comp.gate_speed_pu,
            _rated_slip_rpm(machine) if comp.gate_speed_pu is not None else 0.0,
            comp.gate_speed_rpm,
            TABLE_IV["gate_speed_rpm"],
            _gate_speed_base,
            machine,
        ),
        gate_iq_A=_pick(
            comp.gate_iq_pu,
            machine.rated_current_A,
            comp.gate_iq_A,
            TABLE_IV["gate_iq_A"],
            lambda m: m.rated_current_A,
            machine,
        ),
        gate_band_Hz=band,
    )


def _rotor_corner_Hz(machine) -> float:
    return 1.0 / (2.0 * math.pi * machine.T2_s)


def injection_frequency_Hz(inj, machine, Ts: float, even: bool) -> float:
    """The injection's first frequency without a per-unit one, Hz: ``injection.frequency_Hz``
    as given, or by default Table IV's 2 Hz scaled by the machine's rotor corner
    ``R2 / (2 pi L2)`` (Kubota & Matsuse, IEEE Trans. Ind. Appl. 30(5), 1994: the R2
    information in the flux's answer is the same at a fixed multiple of the corner, not at a
    fixed frequency), moved to a whole number of control periods ``Ts`` (an even number for
    half-period decisions, ``even``) unless it is one already: exactly
    2 Hz on Table IV.

    Parameters
    ----------
    inj : InjectionSettings
        ``[injection]``.
    machine : MachineParams
        The scenario's machine.
    Ts : float
        The control period, s.
    even : bool
        The period must be an even number of control periods.

    Returns
    -------
    float
    """
    if inj.frequency_Hz is not None:
        return inj.frequency_Hz
    f = table_iv_scaled(INJECTION_TABLE_IV_HZ, _rotor_corner_Hz, machine)
    multiple = 2 if even else 1
    periods = 1.0 / (f * Ts)
    n = max(multiple * round(periods / multiple), multiple)
    if abs(periods - n) <= 1e-9 * n:
        return f
    return 1.0 / (n * Ts)
