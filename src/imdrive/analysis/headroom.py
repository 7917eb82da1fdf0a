"""Steady state of a field-oriented drive at a lowered flux: the cost of the estimation headroom.

The injection compensator needs voltage headroom for its sinusoid near and above base speed;
the estimation headroom (:func:`imdrive.kernels.compensator_range.headroom_weakening_input`)
makes it by lowering the rotor flux while estimating. At a given speed and torque a lower flux
needs more torque current and less flux current, so the stator current changes; this module
states that cost in torque per ampere from the steady-state circuit.

With the rotor flux ``psi`` on the d axis (correct orientation, steady state, amplitude-
invariant space vectors, peak values) the standard relations of field orientation hold
(e.g. Novotny & Lipo, *Vector Control and Dynamics of AC Drives*, Oxford 1996, ch. 5)::

    i_d = psi / M,      T = 1.5 n_p (M / L2) psi i_q,      w_sl = R2 M i_q / (L2 psi)
    w_e = n_p w_m + w_sl
    v_d = R1 i_d - w_e sigma L1 i_q,      v_q = R1 i_q + w_e L1 i_d

(the stator flux is ``L1 i_d + j sigma L1 i_q``). Torque per ampere is ``T / |i|``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from imdrive.config.machine import MachineParams
from imdrive.errors import ConfigError


@dataclass(frozen=True)
class OrientedPoint:
    """Steady state of a correctly oriented drive (peak values, controller's frame).

    Attributes
    ----------
    flux_Wb : float
        Rotor flux.
    i_d_A, i_q_A, current_A : float
        Flux and torque currents and the stator current's magnitude.
    v_d_V, v_q_V, voltage_V : float
        The stator voltage and its magnitude (peak phase).
    w_e_rad_s : float
        Stator frequency, electrical rad/s.
    torque_per_ampere : float
        ``|T| / |i|``, N m/A.
    """

    flux_Wb: float
    i_d_A: float
    i_q_A: float
    current_A: float
    v_d_V: float
    v_q_V: float
    voltage_V: float
    w_e_rad_s: float
    torque_per_ampere: float


def oriented_point(
    machine: MachineParams, speed_rpm: float, torque_Nm: float, flux_Wb: float
) -> OrientedPoint:
    """The steady state at ``speed_rpm`` and electromagnetic torque ``torque_Nm`` with the
    rotor flux ``flux_Wb`` (module docstring).

    Raises
    ------
    ConfigError
        ``flux_Wb`` not positive.
    """
    if not flux_Wb > 0.0:
        raise ConfigError("flux_Wb", "must be > 0")
    m = machine
    M = m.M_H
    L1 = m.Ll1_H + M
    L2 = m.Ll2_H + M
    sigma_L1 = L1 - M * M / L2
    n_p = m.pole_pairs
    i_d = flux_Wb / M
    i_q = torque_Nm * L2 / (1.5 * n_p * M * flux_Wb)
    w_sl = m.R2_ohm * M * i_q / (L2 * flux_Wb)
    w_e = n_p * speed_rpm * math.pi / 30.0 + w_sl
    v_d = m.R1_ohm * i_d - w_e * sigma_L1 * i_q
    v_q = m.R1_ohm * i_q + w_e * L1 * i_d
    current = math.hypot(i_d, i_q)
    return OrientedPoint(
        flux_Wb=flux_Wb,
        i_d_A=i_d,
        i_q_A=i_q,
        current_A=current,
        v_d_V=v_d,
        v_q_V=v_q,
        voltage_V=math.hypot(v_d, v_q),
        w_e_rad_s=w_e,
        torque_per_ampere=abs(torque_Nm) / current,
    )


def torque_per_ampere_at_flux(
    machine: MachineParams, speed_rpm: float, torque_Nm: float, flux_Wb: float, factor: float
) -> float:
    """Torque per ampere with the flux lowered to ``factor x flux_Wb``, per unit of that at
    ``flux_Wb`` (below 1: the lowering costs current; the cost is ``1 -`` this).

    Below the flux of maximum torque per ampere (``i_d = |i_q|``) lowering the flux
    *raises* the torque per ampere, so at light load the estimation headroom costs nothing;
    at rated load on Table IV (``i_d < i_q``) it costs.
    """
    if not 0.0 < factor <= 1.0:
        raise ConfigError("factor", "must be in (0, 1]")
    base = oriented_point(machine, speed_rpm, torque_Nm, flux_Wb)
    low = oriented_point(machine, speed_rpm, torque_Nm, factor * flux_Wb)
    return low.torque_per_ampere / base.torque_per_ampere
