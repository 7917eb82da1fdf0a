"""From a :class:`~imdrive.config.scenario.Scenario` to the flat arrays the kernels run on."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imdrive.config.profiles import Profile
from imdrive.config.scenario import Scenario
from imdrive.design.gains import default_current_gains, default_mras_gains, default_speed_gains
from imdrive.errors import ConfigError
from imdrive.fuzzy import fuzzy_table
from imdrive.kernels import layout as Lo
from imdrive.kernels.engine import DRIVE_FOC, DRIVE_OPEN_LOOP
from imdrive.kernels.inverter import INVERTER_CODES
from imdrive.kernels.machine import initial_state
from imdrive.run._profiles import profiles_to_arrays

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm
MAX_LOG_BYTES = 2 * 2**30  # a log larger than this is refused before anything runs


def check_log_size(sc: Scenario) -> None:
    """Refuse a scenario whose log would not fit in :data:`MAX_LOG_BYTES`."""
    sim = sc.simulation
    log_bytes = (sim.n_steps // sim.log_every + 1) * Lo.N_LOG * 8
    if log_bytes > MAX_LOG_BYTES:
        raise ConfigError(
            "simulation.log_every",
            f"the log would take {log_bytes / 2**30:.1f} GiB (limit "
            f"{MAX_LOG_BYTES / 2**30:.0f} GiB): raise simulation.log_every",
        )


@dataclass
class DriveArrays:
    """Everything the compiled loop needs for one drive."""

    par: np.ndarray
    prof_t: np.ndarray
    prof_v: np.ndarray
    prof_n: np.ndarray
    table: np.ndarray
    x0: np.ndarray
    c0: np.ndarray
    n_steps: int
    log_every: int
    derived: dict


def _vf_profiles(sc: Scenario) -> tuple[Profile, Profile]:
    ol = sc.open_loop
    v_peak = ol.voltage_V.scaled(math.sqrt(2.0 / 3.0))
    if ol.vf_ramp_s > 0:
        T = ol.vf_ramp_s
        v_peak = Profile(((0.0, 0.0), (T, v_peak.final)))
        return v_peak, Profile(((0.0, 0.0), (T, ol.frequency_Hz.final)))
    return v_peak, ol.frequency_Hz


def build_arrays(sc: Scenario) -> DriveArrays:
    """Fill the flat parameter, profile and state arrays of :mod:`imdrive.layout`."""
    check_log_size(sc)
    m = sc.machine
    est = sc.estimator
    ctl = sc.control
    th = sc.plant.thermal
    par = np.zeros(Lo.N_PAR)
    par[Lo.P_R1] = m.R1_ohm
    par[Lo.P_R2] = m.R2_ohm
    par[Lo.P_LL1] = m.Ll1_H
    par[Lo.P_LL2] = m.Ll2_H
    par[Lo.P_M] = m.M_H
    par[Lo.P_NP] = m.pole_pairs
    par[Lo.P_J] = m.J_kgm2
    par[Lo.P_B] = m.B_Nms
    par[Lo.P_LOAD_VISC] = sc.load.viscous_Nms
    par[Lo.P_LOAD_FAN] = sc.load.fan_Nms2
    par[Lo.P_ALPHA1] = th.alpha1_per_K
    par[Lo.P_ALPHA2] = th.alpha2_per_K
    par[Lo.P_THETA_REF] = th.theta_ref_C
    par[Lo.P_THETA_AMB] = th.theta_amb_C
    par[Lo.P_RTH1] = th.Rth1_K_per_W
    par[Lo.P_TAU1] = th.tau1_s
    par[Lo.P_RTH2] = th.Rth2_K_per_W
    par[Lo.P_TAU2] = th.tau2_s
    par[Lo.P_THERMAL] = 1.0 if th.enabled else 0.0
    par[Lo.P_MECH_MODE] = 1.0 if sc.plant.speed_mode == "imposed" else 0.0
    par[Lo.P_VDC] = sc.inverter.Vdc_V
    par[Lo.P_INV_MODEL] = INVERTER_CODES[sc.inverter.model]
    par[Lo.P_TS] = sc.simulation.Ts_s
    par[Lo.P_NSUB] = sc.simulation.substeps
    i_div = sc.simulation.divergence_current_A or 100.0 * m.rated_current_A
    par[Lo.P_I_LIMIT_DIV] = i_div
    par[Lo.P_W_LIMIT_DIV] = sc.simulation.divergence_speed_rpm * RPM
    par[Lo.P_DRIVE_MODE] = DRIVE_FOC if sc.drive.mode == "vector" else DRIVE_OPEN_LOOP
    par[Lo.P_SPEED_FB] = 1.0 if ctl.speed_feedback == "mras" else 0.0

    # the controller's own machine model
    R1h = est.R1_ohm if est.R1_ohm is not None else m.R1_ohm
    R2h = est.R2_ohm if est.R2_ohm is not None else m.R2_ohm
    Ll1h = est.Ll1_H if est.Ll1_H is not None else m.Ll1_H
    Ll2h = est.Ll2_H if est.Ll2_H is not None else m.Ll2_H
    Mh = est.M_H if est.M_H is not None else m.M_H
    par[Lo.P_R1_HAT] = R1h
    par[Lo.P_R2_HAT0] = R2h
    par[Lo.P_LL1_HAT] = Ll1h
    par[Lo.P_LL2_HAT] = Ll2h
    par[Lo.P_M_HAT] = Mh

    # gains from bandwidths, each overridable
    L1h, L2h = Ll1h + Mh, Ll2h + Mh
    sigma_L1 = L1h - Mh**2 / L2h
    R_sigma = R1h + (Mh / L2h) ** 2 * R2h
    flux_ref = ctl.flux_ref_Wb or Profile.constant(m.rated_flux_Wb)
    psi0 = flux_ref.points[0][1]
    k_t = 1.5 * m.pole_pairs * Mh / L2h * psi0
    kp_i, ki_i = default_current_gains(sigma_L1, R_sigma, 2 * math.pi * ctl.current_bandwidth_Hz)
    kp_w, ki_w = default_speed_gains(m.J_kgm2, k_t, 2 * math.pi * ctl.speed_bandwidth_Hz)
    K1, K2 = default_mras_gains(psi0, L2h / R2h, 2 * math.pi * sc.mras.bandwidth_Hz)
    gains = {
        "current_kp": ctl.current_kp if ctl.current_kp is not None else kp_i,
        "current_ki": ctl.current_ki if ctl.current_ki is not None else ki_i,
        "speed_kp": ctl.speed_kp if ctl.speed_kp is not None else kp_w,
        "speed_ki": ctl.speed_ki if ctl.speed_ki is not None else ki_w,
        "mras_K1": sc.mras.K1 if sc.mras.K1 is not None else K1,
        "mras_K2": sc.mras.K2 if sc.mras.K2 is not None else K2,
    }
    i_max = ctl.current_limit_A or 2.0 * m.rated_current_A
    par[Lo.P_KP_I] = gains["current_kp"]
    par[Lo.P_KI_I] = gains["current_ki"]
    par[Lo.P_KP_W] = gains["speed_kp"]
    par[Lo.P_KI_W] = gains["speed_ki"]
    par[Lo.P_I_MAX] = i_max
    par[Lo.P_DECOUPLE] = 1.0 if ctl.decoupling else 0.0
    par[Lo.P_WC] = sc.mras.wc_rad_s
    par[Lo.P_K1] = gains["mras_K1"]
    par[Lo.P_K2] = gains["mras_K2"]
    par[Lo.P_I_OFFSET_A] = sc.sensor.i_offset_alpha_A
    par[Lo.P_I_OFFSET_B] = sc.sensor.i_offset_beta_A
    par[Lo.P_LOG_EVERY] = sc.simulation.log_every

    comp = sc.compensator
    Ts = sc.simulation.Ts_s
    inj = sc.injection
    if comp.period_s is not None:
        comp_period = comp.period_s
    elif comp.input == "demodulated":
        comp_period = 1.0 / inj.frequency_Hz
    else:
        comp_period = 0.01
    n_comp = max(int(round(comp_period / Ts)), 1)
    par[Lo.P_INJ_AMP] = inj.amplitude_A
    par[Lo.P_INJ_FREQ] = inj.frequency_Hz
    par[Lo.P_INJ_LPF] = inj.lowpass_rad_s
    par[Lo.P_INJ_T_ON] = inj.t_on_s
    par[Lo.P_COMP_ON] = 1.0 if comp.enabled else 0.0
    par[Lo.P_COMP_T_ON] = comp.t_on_s
    par[Lo.P_COMP_N] = n_comp
    par[Lo.P_COMP_GE] = comp.gain_E_per_Wb
    par[Lo.P_COMP_GDE] = comp.gain_DE_per_Wb
    par[Lo.P_COMP_GCR] = comp.G_CR_ohm
    par[Lo.P_R2_HAT_MIN] = comp.R2_min_ohm if comp.R2_min_ohm is not None else 0.5 * R2h
    par[Lo.P_R2_HAT_MAX] = comp.R2_max_ohm if comp.R2_max_ohm is not None else 2.0 * R2h
    par[Lo.P_COMP_INPUT] = 1.0 if comp.input == "demodulated" else 0.0
    par[Lo.P_COMP_AVG] = 1.0 if comp.average else 0.0
    table = fuzzy_table(comp.table).astype(np.float64)

    v_amp, freq = _vf_profiles(sc)
    profiles = [Profile.constant(0.0)] * Lo.N_PROF
    profiles[Lo.PR_SPEED_REF] = ctl.speed_ref_rpm.scaled(RPM)
    profiles[Lo.PR_LOAD] = sc.load.torque_Nm
    profiles[Lo.PR_R1_SCALE] = sc.plant.R1_scale
    profiles[Lo.PR_R2_SCALE] = sc.plant.R2_scale
    profiles[Lo.PR_V_AMP] = v_amp
    profiles[Lo.PR_FREQ] = freq
    profiles[Lo.PR_SPEED_IMPOSED] = sc.plant.imposed_speed_rpm.scaled(RPM)
    profiles[Lo.PR_FLUX_REF] = flux_ref
    prof_t, prof_v, prof_n = profiles_to_arrays(profiles)

    x0 = initial_state(th.theta_init_C)
    if sc.plant.speed_mode == "imposed":
        x0[Lo.X_W_M] = profiles[Lo.PR_SPEED_IMPOSED](0.0)
    c0 = np.zeros(Lo.NC)
    c0[Lo.C_R2_HAT] = R2h

    derived = dict(gains)
    derived.update(
        {
            "flux_ref_Wb": psi0,
            "torque_constant_Nm_per_A": k_t,
            "current_limit_A": i_max,
            "divergence_current_A": i_div,
            "rated_current_A": m.rated_current_A,
            "sigma": m.sigma,
            "T2_s": m.T2_s,
            "v_max_V": sc.inverter.v_max_V,
            "compensator_period_steps": n_comp,
            "R2_hat_min_ohm": par[Lo.P_R2_HAT_MIN],
            "R2_hat_max_ohm": par[Lo.P_R2_HAT_MAX],
        }
    )
    return DriveArrays(
        par=par,
        prof_t=prof_t,
        prof_v=prof_v,
        prof_n=prof_n,
        table=table,
        x0=x0,
        c0=c0,
        n_steps=sc.simulation.n_steps,
        log_every=sc.simulation.log_every,
        derived=derived,
    )
