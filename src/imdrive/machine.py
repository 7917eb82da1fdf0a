"""Induction machine: parameters (T-equivalent circuit) and the continuous plant model.

State variables (stationary alpha-beta frame, amplitude-invariant Clarke, see :mod:`imdrive`):
stator and rotor flux linkages ``psi_s_ab``, ``psi_r_ab`` (Wb), mechanical speed ``w_m`` (rad/s),
mechanical angle, two winding temperatures and four energy accumulators. With flux linkages as
states the electrical equations are::

    d psi_s/dt = v_s - R1 i_s
    d psi_r/dt = -R2 i_r + j w_r psi_r                     (rotor short-circuited)
    [psi_s; psi_r] = [[L1, M], [M, L2]] [i_s; i_r],  L1 = Ll1 + M,  L2 = Ll2 + M
    T_e = 1.5 n_p (psi_s x i_s)
    J dw_m/dt = T_e - T_L(t, w_m) - B w_m

Winding temperatures follow a first-order thermal model per winding::

    tau dtheta/dt = R_th P_cu - (theta - theta_amb),   R = R_ref (1 + alpha (theta - theta_ref))
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import asdict, dataclass, fields, replace
from importlib import resources

import numpy as np
from numba import njit

from imdrive.errors import ConfigError
from imdrive.layout import (
    P_ALPHA1,
    P_ALPHA2,
    P_B,
    P_J,
    P_LL1,
    P_LL2,
    P_LOAD_FAN,
    P_LOAD_VISC,
    P_M,
    P_MECH_MODE,
    P_NP,
    P_RTH1,
    P_RTH2,
    P_TAU1,
    P_TAU2,
    P_THERMAL,
    P_THETA_AMB,
    P_THETA_REF,
    X_E_CU,
    X_E_EM,
    X_E_IN,
    X_E_LOAD,
    X_PSI_R_A,
    X_PSI_R_B,
    X_PSI_S_A,
    X_PSI_S_B,
    X_TH1,
    X_TH2,
    X_THETA_M,
    X_W_M,
)


@dataclass(frozen=True)
class MachineParams:
    """T-equivalent-circuit parameters of a three-phase induction machine (per phase, SI).

    Parameters
    ----------
    R1_ohm, R2_ohm : float
        Stator and (stator-referred) rotor resistance at the reference temperature, ohm.
    Ll1_H, Ll2_H : float
        Stator and rotor leakage inductance, H.
    M_H : float
        Magnetising (mutual) inductance, H.
    pole_pairs : int
        Number of pole pairs n_p.
    J_kgm2 : float
        Moment of inertia of rotor and load, kg m^2.
    B_Nms : float
        Viscous friction coefficient, N m s/rad.
    rated_power_W, rated_voltage_V, rated_frequency_Hz : float
        Nameplate (shaft power, line-to-line rms voltage, frequency).
    """

    R1_ohm: float
    R2_ohm: float
    Ll1_H: float
    Ll2_H: float
    M_H: float
    pole_pairs: int = 2
    J_kgm2: float = 0.069
    B_Nms: float = 0.0
    rated_power_W: float = 2238.0
    rated_voltage_V: float = 220.0
    rated_frequency_Hz: float = 60.0
    description: str = ""

    def __post_init__(self):
        for name in ("R1_ohm", "R2_ohm", "Ll1_H", "Ll2_H", "M_H", "J_kgm2"):
            _positive(f"machine.{name}", getattr(self, name))
        for name in ("rated_power_W", "rated_voltage_V", "rated_frequency_Hz"):
            _positive(f"machine.{name}", getattr(self, name))
        if isinstance(self.pole_pairs, bool) or not isinstance(self.pole_pairs, int | np.integer):
            raise ConfigError("machine.pole_pairs", "must be an integer")
        if self.pole_pairs < 1:
            raise ConfigError("machine.pole_pairs", "must be >= 1")
        if not math.isfinite(self.B_Nms) or self.B_Nms < 0:
            raise ConfigError("machine.B_Nms", "must be >= 0")

    # derived quantities -------------------------------------------------------------------
    @property
    def L1_H(self) -> float:
        """Stator self-inductance L1 = Ll1 + M, H."""
        return self.Ll1_H + self.M_H

    @property
    def L2_H(self) -> float:
        """Rotor self-inductance L2 = Ll2 + M, H."""
        return self.Ll2_H + self.M_H

    @property
    def sigma(self) -> float:
        """Leakage factor sigma = 1 - M^2 / (L1 L2)."""
        return 1.0 - self.M_H**2 / (self.L1_H * self.L2_H)

    @property
    def T2_s(self) -> float:
        """Rotor time constant T2 = L2 / R2, s."""
        return self.L2_H / self.R2_ohm

    @property
    def rated_flux_Wb(self) -> float:
        """Rotor flux of the machine at rated voltage and frequency, no load, Wb.

        ``(M/L1) * V_phase_peak / w_e`` with ``V_phase_peak = sqrt(2/3) V_ll``.
        """
        v_peak = math.sqrt(2.0 / 3.0) * self.rated_voltage_V
        return self.M_H / self.L1_H * v_peak / (2 * math.pi * self.rated_frequency_Hz)

    @property
    def rated_current_A(self) -> float:
        """Nominal peak phase current, A: rated power over sqrt(3) V_ll, as a peak value.

        Used only to scale limits (controller current limit, divergence bound).
        """
        return math.sqrt(2.0) * self.rated_power_W / (math.sqrt(3.0) * self.rated_voltage_V)

    def with_(self, **changes) -> MachineParams:
        """Return a copy with some fields changed (validated again)."""
        return replace(self, **changes)

    def to_dict(self) -> dict:
        return asdict(self)


def _positive(field: str, value) -> None:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise ConfigError(field, f"must be a number, got {type(value).__name__}")
    if not math.isfinite(value) or value <= 0:
        raise ConfigError(field, f"must be > 0 (got {value})")


def _load_presets() -> dict[str, dict]:
    text = resources.files("imdrive").joinpath("data/machines.toml").read_text()
    return tomllib.loads(text)


def machine_presets() -> dict[str, str]:
    """Names and descriptions of the published machine parameter sets."""
    return {k: v.get("description", "") for k, v in _load_presets().items()}


def machine_preset(name: str = "paper-table-iv", **overrides) -> MachineParams:
    """A published machine parameter set, optionally with fields overridden.

    ``paper-table-iv`` (the paper's Table IV, J = 0.069 kg m^2) and ``krause-3hp`` (the textbook
    machine it comes from, J = 0.089 kg m^2).
    """
    presets = _load_presets()
    if name not in presets:
        raise ConfigError("machine.preset", f"unknown preset {name!r}; known: {sorted(presets)}")
    data = {k: v for k, v in presets[name].items() if k != "source"}
    known = {f.name for f in fields(MachineParams)}
    for k in overrides:
        if k not in known:
            raise ConfigError(f"machine.{k}", "unknown field")
    data.update(overrides)
    return MachineParams(**data)


# ------------------------------------------------------------------------------------------
# compiled kernels


@njit(cache=True)
def currents_from_fluxes(psi_s_a, psi_s_b, psi_r_a, psi_r_b, L1, L2, M):
    """Stator and rotor currents from the flux linkages, A.

    Inverts ``[psi_s; psi_r] = [[L1, M], [M, L2]] [i_s; i_r]``.
    """
    inv_d = 1.0 / (L1 * L2 - M * M)
    i_s_a = (L2 * psi_s_a - M * psi_r_a) * inv_d
    i_s_b = (L2 * psi_s_b - M * psi_r_b) * inv_d
    i_r_a = (L1 * psi_r_a - M * psi_s_a) * inv_d
    i_r_b = (L1 * psi_r_b - M * psi_s_b) * inv_d
    return i_s_a, i_s_b, i_r_a, i_r_b


@njit(cache=True)
def winding_resistances(x, par, R1_base, R2_base):
    """Actual R1, R2 (ohm): the profile-scaled base values times the thermal factor."""
    if par[P_THERMAL] != 0.0:
        R1 = R1_base * (1.0 + par[P_ALPHA1] * (x[X_TH1] - par[P_THETA_REF]))
        R2 = R2_base * (1.0 + par[P_ALPHA2] * (x[X_TH2] - par[P_THETA_REF]))
        return R1, R2
    return R1_base, R2_base


@njit(cache=True)
def load_torque(par, TL0, w_m):
    """Load torque T_L = T0(t) + b w_m + k_fan w_m |w_m|, N m (positive opposes forward motion)."""
    return TL0 + par[P_LOAD_VISC] * w_m + par[P_LOAD_FAN] * w_m * abs(w_m)


@njit(cache=True)
def electromagnetic_torque(psi_s_a, psi_s_b, i_s_a, i_s_b, n_p):
    """T_e = 1.5 n_p (psi_s x i_s), N m."""
    return 1.5 * n_p * (psi_s_a * i_s_b - psi_s_b * i_s_a)


@njit(cache=True)
def machine_derivative(x, v_a, v_b, R1_base, R2_base, TL0, par, dx):
    """Time derivative of the plant state (writes ``dx``).

    Parameters
    ----------
    x : float64[NX]
        Plant state (layout ``X_*``).
    v_a, v_b : float
        Stator voltage space vector applied by the inverter, V.
    R1_base, R2_base : float
        Resistances at the reference temperature, already scaled by their time profiles, ohm.
    TL0 : float
        Time-dependent part of the load torque, N m.
    par : float64[N_PAR]
    dx : float64[NX]
        Output.
    """
    L1 = par[P_LL1] + par[P_M]
    L2 = par[P_LL2] + par[P_M]
    M = par[P_M]
    n_p = par[P_NP]
    psi_s_a = x[X_PSI_S_A]
    psi_s_b = x[X_PSI_S_B]
    psi_r_a = x[X_PSI_R_A]
    psi_r_b = x[X_PSI_R_B]
    w_m = x[X_W_M]
    R1, R2 = winding_resistances(x, par, R1_base, R2_base)
    i_s_a, i_s_b, i_r_a, i_r_b = currents_from_fluxes(psi_s_a, psi_s_b, psi_r_a, psi_r_b, L1, L2, M)
    w_r = n_p * w_m
    dx[X_PSI_S_A] = v_a - R1 * i_s_a
    dx[X_PSI_S_B] = v_b - R1 * i_s_b
    dx[X_PSI_R_A] = -R2 * i_r_a - w_r * psi_r_b
    dx[X_PSI_R_B] = -R2 * i_r_b + w_r * psi_r_a
    T_e = electromagnetic_torque(psi_s_a, psi_s_b, i_s_a, i_s_b, n_p)
    T_L = load_torque(par, TL0, w_m)
    if par[P_MECH_MODE] == 0.0:
        dx[X_W_M] = (T_e - T_L - par[P_B] * w_m) / par[P_J]
    else:  # speed imposed: the engine writes x[X_W_M] from its profile every period
        dx[X_W_M] = 0.0
    dx[X_THETA_M] = w_m
    p_cu1 = 1.5 * R1 * (i_s_a * i_s_a + i_s_b * i_s_b)
    p_cu2 = 1.5 * R2 * (i_r_a * i_r_a + i_r_b * i_r_b)
    if par[P_THERMAL] != 0.0:
        dx[X_TH1] = (par[P_RTH1] * p_cu1 - (x[X_TH1] - par[P_THETA_AMB])) / par[P_TAU1]
        dx[X_TH2] = (par[P_RTH2] * p_cu2 - (x[X_TH2] - par[P_THETA_AMB])) / par[P_TAU2]
    else:
        dx[X_TH1] = 0.0
        dx[X_TH2] = 0.0
    dx[X_E_IN] = 1.5 * (v_a * i_s_a + v_b * i_s_b)
    dx[X_E_CU] = p_cu1 + p_cu2
    dx[X_E_EM] = T_e * w_m
    dx[X_E_LOAD] = (T_L + par[P_B] * w_m) * w_m


@njit(cache=True)
def magnetic_energy(x, par):
    """Energy stored in the magnetic field, 1.5 * 0.5 * (psi_s.i_s + psi_r.i_r), J."""
    L1 = par[P_LL1] + par[P_M]
    L2 = par[P_LL2] + par[P_M]
    i_s_a, i_s_b, i_r_a, i_r_b = currents_from_fluxes(
        x[X_PSI_S_A], x[X_PSI_S_B], x[X_PSI_R_A], x[X_PSI_R_B], L1, L2, par[P_M]
    )
    return 0.75 * (
        x[X_PSI_S_A] * i_s_a + x[X_PSI_S_B] * i_s_b + x[X_PSI_R_A] * i_r_a + x[X_PSI_R_B] * i_r_b
    )


def initial_state(theta_init_C: float = 20.0, w_m0: float = 0.0) -> np.ndarray:
    """Plant state at rest, demagnetised, windings at ``theta_init_C``."""
    from imdrive.layout import NX

    x = np.zeros(NX)
    x[X_W_M] = w_m0
    x[X_TH1] = theta_init_C
    x[X_TH2] = theta_init_C
    return x
