"""Machine-dependent settings first tuned in SI on the paper's Table IV machine, resolved on the
scenario's machine: the absolute key when given, its per-unit twin times the machine's base
quantity, or by default Table IV's number scaled by that base
(:func:`imdrive.config.perunit.table_iv_scaled`: exactly the old number on Table IV).

==============================================  ==============================================
per-unit key                                    base it multiplies
==============================================  ==============================================
``ekf.voltage_noise_pu``                        the rated phase voltage's peak
                                                ``sqrt(2/3) V_ll`` (:func:`rated_phase_peak_V`)
``ekf.current_noise_pu``                        the rated peak current
``ekf.flux_noise_pu``                           ``psi_rated / T2``, the rotor flux's own rate
``ekf.acceleration_noise_pu``                   the rated acceleration ``n_p T_rated / J``
                                                (electrical, :func:`rated_acceleration_rad_s2`)
``ekf.R2_drift_pu``                             ``R2 / T2``: R2 per rotor time constant
``plant.thermal.Rth1_pu``, ``Rth2_pu``          ``80 K / P_cu,rated``: the class B temperature
                                                rise over the winding's rated copper losses
                                                (:func:`plant_thermal_resistances`)
``afo.R1_bandwidth_pu``, ``R2_bandwidth_pu``    the rotor corner ``1 / T2`` (rad/s), as
                                                ``mras.R1_rate_pu``
                                                (:func:`afo_resistance_bandwidths`)
``flux_injection.frequency_pu``                 the controller's rotor corner
                                                ``R2_hat(0) / (2 pi L2_hat)``, as
                                                ``injection.frequency_pu``; unset, Table IV's
                                                2 Hz scaled by the machine's corner
                                                (:func:`flux_injection_frequency_Hz`)
==============================================  ==============================================

Each pair is declared in :data:`imdrive.config.pairs.PAIRS`. :mod:`imdrive.config.perunit`
resolves the settings the compensator, injection and limits share; this module holds the
others (perunit's size), and imports it, never the other way.
"""

from __future__ import annotations

import math

from imdrive.config.perunit import rated_peak_current_A, resolve, table_iv_scaled
from imdrive.errors import ConfigError

__all__ = [
    "EKF_NOISE",
    "afo_resistance_bandwidths",
    "RISE_BASE_K",
    "ekf_noise",
    "flux_injection_frequency_Hz",
    "plant_thermal_resistances",
    "rated_copper_losses_W",
    "rated_acceleration_rad_s2",
    "rated_phase_peak_V",
    "rotor_corner_Hz",
    "rotor_flux_rate_Wb_s",
    "rotor_resistance_rate_ohm_s",
]


def rated_phase_peak_V(machine) -> float:
    """The rated phase voltage's peak, the space vector's magnitude, V: ``sqrt(2/3) V_ll``."""
    return math.sqrt(2.0 / 3.0) * machine.rated_voltage_V


def rated_acceleration_rad_s2(machine) -> float:
    """The electrical acceleration the rated torque gives the machine's inertia, rad/s^2:
    ``n_p T_rated / J`` (Table IV 360, Aalto 2.2 kW 1947, Krause 500 hp 363). A circuit without
    a rated point takes the rated power at the synchronous speed for ``T_rated``."""
    from imdrive.config.machine import rated_point

    try:
        torque = rated_point(machine).torque_Nm
    except ConfigError:
        torque = (
            machine.rated_power_W * machine.pole_pairs / (2 * math.pi * machine.rated_frequency_Hz)
        )
    return machine.pole_pairs * torque / machine.J_kgm2


def rotor_flux_rate_Wb_s(machine) -> float:
    """``psi_rated / T2``, Wb/s: the rate at which the rotor flux settles, the scale of its
    model's R2-dependent term ``(M i - psi) / T2``."""
    return machine.rated_flux_Wb / machine.T2_s


def rotor_resistance_rate_ohm_s(machine) -> float:
    """``R2 / T2``, ohm/s: R2 over one rotor time constant. The R2 error shows in the flux
    through the rotor's corner ``1/T2``, so the R2 state's random walk, which sets how fast
    the filter lets R̂2 move, is stated in this unit, as ``mras.R1_rate_pu`` states the online
    R1 law's rate in ``1/T2``: the estimate's bandwidth then stays as far below the flux
    injection (whose frequency scales with the corner) on every machine."""
    return machine.R2_ohm / machine.T2_s


#: The EKF's noise settings: ``(absolute key, per-unit key, Table IV's value, base)``; each
#: process noise is the uncertainty of its state's derivative, the measurement noise the
#: sensors'; each scales with the machine's quantity named (module docstring).
EKF_NOISE: tuple[tuple[str, str, float, object], ...] = (
    ("voltage_noise_V", "voltage_noise_pu", 5.0, rated_phase_peak_V),
    ("flux_noise_Wb_per_s", "flux_noise_pu", 0.1, rotor_flux_rate_Wb_s),
    ("acceleration_noise_rad_s2", "acceleration_noise_pu", 2000.0, rated_acceleration_rad_s2),
    ("R2_drift_ohm_per_s", "R2_drift_pu", 0.5, rotor_resistance_rate_ohm_s),
    ("current_noise_A", "current_noise_pu", 0.05, rated_peak_current_A),
)


def ekf_noise(ekf, machine) -> tuple[float, float, float, float, float]:
    """The EKF's noise settings in SI on ``machine``, in the order of :data:`EKF_NOISE`
    (voltage V, flux Wb/s, acceleration rad/s^2, R2 drift ohm/s, current A): each absolute key
    when set, its per-unit twin times the base, or Table IV's value scaled by the base.

    Parameters
    ----------
    ekf : EkfSettings
        The ``[ekf]`` section.
    machine : MachineParams
        The scenario's machine.

    Returns
    -------
    tuple of float
    """
    return tuple(
        _given_or_scaled(getattr(ekf, absolute), getattr(ekf, per_unit), table_iv, base, machine)
        for absolute, per_unit, table_iv, base in EKF_NOISE
    )


def _given_or_scaled(absolute, per_unit, table_iv: float, base, machine) -> float:
    """``absolute`` when set, else ``per_unit x base(machine)``, else Table IV's value scaled
    by the base (:func:`table_iv_scaled`)."""
    if absolute is not None:
        return absolute
    if per_unit is not None:
        return per_unit * base(machine)
    return table_iv_scaled(table_iv, base, machine)


#: The temperature rise the plant's thermal resistances are stated in, K: the class B limit of
#: IEC 60034-1 (the default of ``compensator.thermal_rise_K``, the controller's own model).
RISE_BASE_K = 80.0

#: The plant's thermal resistances on Table IV, K/W (stator, rotor).
RTH_TABLE_IV_K_PER_W = (0.4, 0.4)


def rated_copper_losses_W(machine) -> tuple[float, float]:
    """The machine's copper losses at its rated point, W: stator ``1.5 R1 I_peak^2`` (the
    rated current, amplitude-invariant), rotor ``s T_rated w_sync`` (the slip times the
    air-gap power; :func:`imdrive.config.perunit.rated_rotor_loss_W`).

    Raises
    ------
    ConfigError
        The machine has no rated point (naming ``plant.thermal.enabled``).
    """
    from imdrive.config.machine import rated_point

    try:
        rp = rated_point(machine)
    except ConfigError as exc:
        raise ConfigError(
            "plant.thermal.enabled",
            f"needs the machine's rated point or Rth1_K_per_W and Rth2_K_per_W ({exc})",
        ) from exc
    w_sync = rp.synchronous_speed_rpm * math.pi / 30.0
    return 1.5 * machine.R1_ohm * rp.current_peak_A**2, rp.slip * rp.torque_Nm * w_sync


def plant_thermal_resistances(sc) -> tuple[float, float]:
    """The plant's winding-to-ambient thermal resistances (stator, rotor), K/W.

    Each is ``plant.thermal.RthN_K_per_W`` when set; else ``RthN_pu`` times
    ``RISE_BASE_K / P_cu,rated`` (:func:`rated_copper_losses_W`), so the per-unit value is the
    winding's steady rise at its rated losses over the class B limit; unset, Table IV's
    0.4 K/W scaled by ``1 / P_cu,rated`` (:func:`table_iv_scaled`: exactly 0.4 on Table IV,
    whose rated losses 85.7 W and 102.8 W then rise 34 K and 41 K; a fixed 0.4 K/W would put
    the rotor of Krause 500 hp, 5.7 kW, at 2300 K).

    The thermal time constants ``tau1_s``, ``tau2_s`` stay absolute (1200 s): a published
    scaling of a winding's thermal time constant with the machine's size was not found; it
    depends on the enclosure and cooling as much as on the rating.

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    tuple of float
    """
    th = sc.plant.thermal
    given = (th.Rth1_K_per_W, th.Rth2_K_per_W)
    per_unit = (th.Rth1_pu, th.Rth2_pu)
    if all(v is not None for v in given):
        return given
    losses = rated_copper_losses_W(sc.machine)
    out = []
    for i in range(2):
        if given[i] is not None:
            out.append(given[i])
        elif per_unit[i] is not None:
            out.append(per_unit[i] * RISE_BASE_K / losses[i])
        else:
            inverse_loss = lambda m, i=i: 1.0 / rated_copper_losses_W(m)[i]  # noqa: E731
            out.append(table_iv_scaled(RTH_TABLE_IV_K_PER_W[i], inverse_loss, sc.machine))
    return tuple(out)


#: The flux-command injection's frequency on Table IV, Hz (1.098 x its rotor corner, 1.82 Hz).
FLUX_INJECTION_TABLE_IV_HZ = 2.0


def rotor_corner_Hz(machine) -> float:
    """The machine's rotor corner frequency ``R2 / (2 pi L2)``, Hz."""
    return 1.0 / (2.0 * math.pi * machine.T2_s)


def flux_injection_frequency_Hz(sc) -> float:
    """The frequency of the sinusoid on the flux command (``[flux_injection]``), Hz.

    ``flux_injection.frequency_Hz`` when set; else ``frequency_pu`` times the controller's rotor
    corner ``R2_hat(0) / (2 pi L2_hat)`` (:func:`imdrive.config.perunit.resolve`, the base of
    ``injection.frequency_pu``); unset, Table IV's 2 Hz scaled by the machine's corner
    ``R2 / (2 pi L2)`` (:func:`table_iv_scaled`: exactly 2 Hz on Table IV whatever the
    controller's starting R̂2; 0.22 Hz on Krause 500 hp, 1.6 Hz on Aalto 2.2 kW). The
    excitation is Kubota & Matsuse's (IEEE Trans. Ind. Appl. 30(5), 1994); the rotor flux's
    response to the flux current, ``M / (1 + j w T2)``, depends on R2 through ``w T2`` alone,
    so the R2 information in the swing is the same on every machine at a fixed multiple of
    the corner, not at a fixed frequency (2 Hz is 20 times the corner of Krause 2250 hp,
    where the swing's R2 dependence has all but vanished).

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    float
    """
    fi = sc.flux_injection
    if fi.frequency_Hz is not None:
        return fi.frequency_Hz
    if fi.frequency_pu is not None:
        r = resolve(sc)
        return fi.frequency_pu * r.R2_hat / (2.0 * math.pi * (r.Ll2_hat + r.M_hat))
    return table_iv_scaled(FLUX_INJECTION_TABLE_IV_HZ, rotor_corner_Hz, sc.machine)


#: The AFO's R1 and R2 adaptation rates on Table IV, rad/s (0.175 x its 1/T2 = 11.4 /s).
AFO_BANDWIDTHS_TABLE_IV_RAD_S = (2.0, 2.0)


def _rotor_corner_rad_s(machine) -> float:
    return 1.0 / machine.T2_s


def afo_resistance_bandwidths(afo, machine) -> tuple[float, float]:
    """The adaptive flux observer's R̂1 and R̂2 adaptation rates, rad/s.

    Each is ``afo.RN_bandwidth_rad_s`` when set; else ``RN_bandwidth_pu`` times the machine's
    rotor corner ``1 / T2``; unset, Table IV's 2 rad/s scaled by it (:func:`table_iv_scaled`:
    exactly 2 rad/s on Table IV, 0.22 on Krause 500 hp, 1.6 on Aalto 2.2 kW). The resistances
    show in the flux through the rotor's corner, and the R2 law runs on the flux injection,
    whose frequency scales with the corner (:func:`flux_injection_frequency_Hz`): a fixed
    2 rad/s is 3.2 times the corner of Krause 2250 hp, and above that injection's 0.69 rad/s.

    Parameters
    ----------
    afo : AfoSettings
        The ``[afo]`` section.
    machine : MachineParams
        The scenario's machine.

    Returns
    -------
    tuple of float
    """
    out = []
    given = (afo.R1_bandwidth_rad_s, afo.R2_bandwidth_rad_s)
    per_unit = (afo.R1_bandwidth_pu, afo.R2_bandwidth_pu)
    for g, pu, table_iv in zip(given, per_unit, AFO_BANDWIDTHS_TABLE_IV_RAD_S, strict=True):
        out.append(_given_or_scaled(g, pu, table_iv, _rotor_corner_rad_s, machine))
    return tuple(out)
