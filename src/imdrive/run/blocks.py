"""One builder per block: its records from the scenario, filled by field name.

Each function turns the settings of one block into its record (``(1,)`` arrays of the block's
dtype, :func:`imdrive.kernels.records.new_record`), with the gain design where the block has
one. :func:`imdrive.run.build.build_arrays` assembles them into a drive; the estimator's
records come from its own builder (:mod:`imdrive.run.estimators`).
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.config.compensator import decision_period_steps
from imdrive.config.perunit import (
    current_limit_A,
    divergence_current_A,
    divergence_speed_rpm,
    resolve,
    speed_bandwidth_Hz,
)
from imdrive.config.profiles import Profile
from imdrive.config.scenario import Scenario
from imdrive.design.gains import default_current_gains, default_speed_gains
from imdrive.errors import ConfigError
from imdrive.fuzzy import fuzzy_table
from imdrive.kernels import profiles as kp
from imdrive.kernels.compensator import COMPENSATOR_PARAMS, COMPENSATOR_STATE
from imdrive.kernels.engine import DRIVE_FOC, DRIVE_OPEN_LOOP, SAMPLE_STATE, SIM_PARAMS, DriveState
from imdrive.kernels.ifoc import CONTROL_PARAMS, CONTROL_STATE
from imdrive.kernels.inverter import INVERTER_CODES, INVERTER_PARAMS, INVERTER_STATE
from imdrive.kernels.machine import PLANT_PARAMS, initial_plant_state, saturation_table
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.records import new_record
from imdrive.kernels.sensors import SENSOR_PARAMS
from imdrive.run._profiles import profiles_to_arrays

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm


def saturation_curve(sc: Scenario) -> dict:
    """The plant's magnetising-curve fields (see ``SaturationSettings``)."""
    sat = sc.plant.saturation
    m = sc.machine
    rho, S = sat.rated_ratio, sat.exponent
    Lm0 = sat.Lm0_H if sat.Lm0_H is not None else m.M_H / rho
    psi_sat = sat.psi_sat_Wb
    if psi_sat is None:
        psi_sat = m.rated_flux_Wb * (rho / (1.0 - rho)) ** (1.0 / S)
    fields = {"saturation": sat.enabled, "Lm0": Lm0, "psi_sat": psi_sat, "S": S}
    if sat.enabled:  # the inverse curve tabulated once per run (no Newton loop per step)
        table = saturation_table(m.Ll1_H, m.Ll2_H, Lm0, psi_sat, S)
        table.pop("sat_table_error")
        fields.update(table)
    return fields


def plant_record(sc: Scenario) -> np.ndarray:
    """``PLANT_PARAMS``: the machine, its load, thermal model and saturation."""
    m = sc.machine
    th = sc.plant.thermal
    return new_record(
        PLANT_PARAMS,
        R1=m.R1_ohm,
        R2=m.R2_ohm,
        Ll1=m.Ll1_H,
        Ll2=m.Ll2_H,
        M=m.M_H,
        n_p=m.pole_pairs,
        J=m.J_kgm2,
        B=m.B_Nms,
        k_visc=sc.load.viscous_Nms,
        k_fan=sc.load.fan_Nms2,
        alpha1=th.alpha1_per_K,
        alpha2=th.alpha2_per_K,
        theta_ref=th.theta_ref_C,
        theta_amb=th.theta_amb_C,
        Rth1=th.Rth1_K_per_W,
        tau1=th.tau1_s,
        Rth2=th.Rth2_K_per_W,
        tau2=th.tau2_s,
        thermal=th.enabled,
        speed_imposed=sc.plant.speed_mode == "imposed",
        **saturation_curve(sc),
    )


def divergence_current(sc: Scenario) -> float:
    """The current beyond which a run counts as diverged, A."""
    return divergence_current_A(sc)


def sim_record(sc: Scenario) -> np.ndarray:
    """``SIM_PARAMS``: the loop's period, sub-steps, divergence bounds and mode."""
    ctl = sc.control
    return new_record(
        SIM_PARAMS,
        Ts=sc.simulation.Ts_s,
        nsub=sc.simulation.substeps,
        i_lim=divergence_current(sc),
        w_lim=divergence_speed_rpm(sc) * RPM,
        mode=DRIVE_FOC if sc.drive.mode == "vector" else DRIVE_OPEN_LOOP,
        sensorless=ctl.speed_feedback != "measured",
        delay=ctl.delay_periods,
        flux_inj_amp=sc.flux_injection.amplitude,
        flux_inj_freq=sc.flux_injection.frequency_Hz,
    )


def inverter_record(sc: Scenario) -> np.ndarray:
    """``INVERTER_PARAMS``: DC link, model, dead time, device drop, switching frequency."""
    inv = sc.inverter
    return new_record(
        INVERTER_PARAMS,
        Vdc=inv.Vdc_V,
        model=INVERTER_CODES[inv.model],
        t_d=inv.dead_time_s,
        v_drop=inv.device_drop_V,
        i_band=inv.sign_band_A,
        f_sw=inv.switching_frequency_Hz,
    )


def sensor_record(sc: Scenario) -> np.ndarray:
    """``SENSOR_PARAMS``: current sensors (offsets, gains, noise, ADC) and the DC-link gain."""
    sen = sc.sensor
    return new_record(
        SENSOR_PARAMS,
        i_offset_ab=complex(sen.i_offset_alpha_A, sen.i_offset_beta_A),
        phase_model=sen.per_phase,
        gain_a=sen.gain_a,
        gain_b=sen.gain_b,
        offset_a=sen.offset_a_A,
        offset_b=sen.offset_b_A,
        noise_rms=sen.noise_rms_A,
        adc_bits=sen.adc_bits or 0,
        adc_range=sen.adc_range_A,
        seed=sen.seed,
        vdc_gain=sen.vdc_gain,
    )


def model_record(sc: Scenario) -> tuple[np.ndarray, dict]:
    """``MODEL_STATE`` (the controller's machine model: its estimates, absolute or as ratios of
    the plant's, :func:`imdrive.config.perunit.resolve`; unset: the plant's) and the
    model's inductances ``R1_hat, R2_hat, M_hat, L1_hat, L2_hat, sigma_L1_hat`` as a dict."""
    r = resolve(sc)
    R1h, R2h, Ll1h, Ll2h, Mh = r.R1_hat, r.R2_hat, r.Ll1_hat, r.Ll2_hat, r.M_hat
    model = new_record(MODEL_STATE, R1_hat=R1h, R2_hat=R2h, Ll1_hat=Ll1h, Ll2_hat=Ll2h, M_hat=Mh)
    L1h, L2h = Ll1h + Mh, Ll2h + Mh
    sigma_L1 = L1h - Mh**2 / L2h
    mh = dict(R1_hat=R1h, R2_hat=R2h, M_hat=Mh, L1_hat=L1h, L2_hat=L2h, sigma_L1_hat=sigma_L1)
    return model, mh


def flux_reference(sc: Scenario) -> Profile:
    """The rotor-flux reference profile, Wb (default: the machine's rated flux)."""
    return sc.control.flux_ref_Wb or Profile.constant(sc.machine.rated_flux_Wb)


def _assumed_dead_time(sc: Scenario) -> float:
    """The dead time the controller's compensation assumes, s (default: the inverter's)."""
    t = sc.control.dead_time_compensation_s
    return sc.inverter.dead_time_s if t is None else t


def control_record(sc: Scenario, mh: dict, psi0: float) -> tuple[np.ndarray, dict]:
    """``CONTROL_PARAMS`` and the controller's gains (current and speed PI from bandwidths,
    each overridable), from the model ``mh`` of :func:`model_record` and flux ``psi0``."""
    m = sc.machine
    ctl = sc.control
    inv = sc.inverter
    Vdc_meas = sc.sensor.vdc_gain * inv.Vdc_V
    R_sigma = mh["R1_hat"] + (mh["M_hat"] / mh["L2_hat"]) ** 2 * mh["R2_hat"]
    k_t = 1.5 * m.pole_pairs * mh["M_hat"] / mh["L2_hat"] * psi0
    kp_i, ki_i = default_current_gains(
        mh["sigma_L1_hat"], R_sigma, 2 * math.pi * ctl.current_bandwidth_Hz
    )
    kp_w, ki_w = default_speed_gains(m.J_kgm2, k_t, 2 * math.pi * speed_bandwidth_Hz(sc))
    gains = {
        "current_kp": ctl.current_kp if ctl.current_kp is not None else kp_i,
        "current_ki": ctl.current_ki if ctl.current_ki is not None else ki_i,
        "speed_kp": ctl.speed_kp if ctl.speed_kp is not None else kp_w,
        "speed_ki": ctl.speed_ki if ctl.speed_ki is not None else ki_w,
    }
    control = new_record(
        CONTROL_PARAMS,
        n_p=m.pole_pairs,
        kp_w=gains["speed_kp"],
        ki_w=gains["speed_ki"],
        kp_i=gains["current_kp"],
        ki_i=gains["current_ki"],
        i_max=current_limit(sc),
        v_max=Vdc_meas / math.sqrt(3.0),
        decouple=ctl.decoupling,
        angle_advance=0.5 + (ctl.delay_periods if ctl.delay_compensation else 0),
        dtc_u=(
            _assumed_dead_time(sc) * inv.switching_frequency_Hz * Vdc_meas
            if ctl.dead_time_compensation == "feedforward"
            else 0.0
        ),
        dtc_band=inv.sign_band_A,
        fw=ctl.field_weakening,
        fw_v=ctl.field_weakening_voltage,
        fw_rate=ctl.field_weakening_rate,
        fw_min=ctl.field_weakening_min,
    )
    return control, gains


def current_limit(sc: Scenario) -> float:
    """The controller's current limit, A (:func:`imdrive.config.perunit.current_limit_A`)."""
    return current_limit_A(sc)


def compensator_period(sc: Scenario) -> int:
    """The compensator's decision period in control periods (whole injection periods, checked
    by the scenario: :func:`~imdrive.config.compensator.check_whole_injection_periods`)."""
    return decision_period_steps(sc.compensator, sc.injection, sc.simulation.Ts_s, resolve(sc))


def compensator_record(sc: Scenario) -> tuple[np.ndarray, dict]:
    """``COMPENSATOR_PARAMS`` (fuzzy compensator, injection, gating, step law) and what to
    report; gains, clamps and amplitude absolute or in per-unit of the machine
    (:func:`imdrive.config.perunit.resolve`)."""
    comp = sc.compensator
    inj = sc.injection
    r = resolve(sc)
    n_comp = compensator_period(sc)
    R2_min = r.R2_min
    R2_max = r.R2_max
    record = new_record(
        COMPENSATOR_PARAMS,
        enabled=comp.enabled,
        t_on=comp.t_on_s,
        n=n_comp,
        G_E=r.gain_E,
        G_DE=r.gain_DE,
        G_CR=r.G_CR,
        R2_min=R2_min,
        R2_max=R2_max,
        demodulated=comp.input == "demodulated",
        average=comp.average,
        inj_amp=r.inj_amp,
        inj_freq=r.inj_f1,
        inj_lpf=inj.lowpass_rad_s,
        inj_t_on=inj.t_on_s,
        inj_hp_wc=sc.mras.wc_rad_s if inj.compensate_filter else 0.0,
        **_gating(sc, r),
    )
    derived = {
        "compensator_period_steps": n_comp,
        "R2_hat_min_ohm": R2_min,
        "R2_hat_max_ohm": R2_max,
    }
    return record, derived


def _gating(sc, r) -> dict:
    """The compensator's gating, frequency-schedule and step-law parameters (off: zeros)."""
    comp = sc.compensator
    on = comp.gating if comp.gating is not None else comp.input == "demodulated"
    out = {}
    inj = sc.injection
    headroom = inj.headroom if inj.headroom is not None else sc.control.field_weakening
    if headroom and r.inj_amp > 0.0:
        if not inj.headroom_from < inj.headroom_to:
            raise ConfigError("injection.headroom_from", "must be < injection.headroom_to")
        out["inj_v_lo"] = inj.headroom_from
        out["inj_v_hi"] = inj.headroom_to
    if comp.step_law == "adaptive":
        dmax = comp.drift_max_ohm if comp.drift_max_ohm is not None else 3.0 * r.G_CR
        out |= {
            "fine": True,
            "fine_gain": comp.fine_gain,
            "drift_gain": comp.drift_gain,
            "drift_max": dmax,
            "drift_fmin": _drift_fmin(sc, r),
        }
    if not (on and comp.enabled):
        return out
    f2 = r.inj_f2
    band = r.gate_band
    injecting = r.inj_amp > 0.0
    return out | {
        "gate": True,
        "gate_dw": r.gate_speed_rpm * RPM,
        "gate_diq": r.gate_iq_A,
        "gate_v": comp.gate_voltage,
        "gate_df": band if injecting else 0.0,
        "gate_hold": float(comp.gate_hold_periods),
        "inj_freq2": f2 if injecting and band > 0 else 0.0,
        "inj_freq3": (r.inj_f3 if r.inj_f3 is not None and injecting and band > 0 else 0.0),
    }


def _drift_fmin(sc, r) -> float:
    """Stator frequency below which the adaptive law has no drift term, Hz (0: never)."""
    comp = sc.compensator
    if comp.drift_min_freq_Hz is not None:
        return comp.drift_min_freq_Hz
    if r.inj_amp <= 0.0:
        return 0.0
    return max(r.inj_f1, r.inj_f2)


def fuzzy_lookup_table(sc: Scenario) -> np.ndarray:
    """The compensator's 13 x 13 lookup table (``compensator.table``)."""
    return fuzzy_table(sc.compensator.table).astype(np.float64)


def _vf_profiles(sc: Scenario) -> tuple[Profile, Profile]:
    ol = sc.open_loop
    v_peak = ol.voltage_V.scaled(math.sqrt(2.0 / 3.0))
    if ol.vf_ramp_s > 0:
        T = ol.vf_ramp_s
        v_peak = Profile(((0.0, 0.0), (T, v_peak.final)))
        return v_peak, Profile(((0.0, 0.0), (T, ol.frequency_Hz.final)))
    return v_peak, ol.frequency_Hz


def profile_list(sc: Scenario) -> list[Profile]:
    """Every profile the kernels read, in the order of ``kernels/profiles.py`` (SI units)."""
    v_amp, freq = _vf_profiles(sc)
    profiles = [Profile.constant(0.0)] * kp.N_PROF
    profiles[kp.PR_SPEED_REF] = sc.control.speed_ref_rpm.scaled(RPM)
    profiles[kp.PR_LOAD] = sc.load.torque_Nm
    profiles[kp.PR_R1_SCALE] = sc.plant.R1_scale
    profiles[kp.PR_R2_SCALE] = sc.plant.R2_scale
    profiles[kp.PR_V_AMP] = v_amp
    profiles[kp.PR_FREQ] = freq
    profiles[kp.PR_SPEED_IMPOSED] = sc.plant.imposed_speed_rpm.scaled(RPM)
    profiles[kp.PR_FLUX_REF] = flux_reference(sc)
    return profiles


def profile_arrays(sc: Scenario):
    """The profiles as the kernels' breakpoint arrays ``(prof_t, prof_v, prof_n)``."""
    return profiles_to_arrays(profile_list(sc))


def _compensator_state(sc) -> np.ndarray:
    """Initial COMPENSATOR_STATE: zeros (no previous iq* yet), the injection frequency in use."""
    st = np.zeros(1, dtype=COMPENSATOR_STATE)
    f1 = resolve(sc).inj_f1
    st[0]["inj_f"] = f1
    st[0]["inj_f_prev"] = f1
    return st


def initial_state(sc: Scenario, model: np.ndarray, est_state: np.ndarray) -> DriveState:
    """The drive's initial state: plant at rest (or at the imposed speed), the controller's
    model, the estimator's initial state, the rest zeros."""
    imposed = sc.plant.speed_mode == "imposed"
    w_m0 = sc.plant.imposed_speed_rpm.scaled(RPM)(0.0) if imposed else 0.0
    return DriveState(
        plant=initial_plant_state(sc.plant.thermal.theta_init_C, w_m0),
        sample=np.zeros(1, dtype=SAMPLE_STATE),
        model=model,
        control=np.zeros(1, dtype=CONTROL_STATE),
        est=est_state,
        comp=_compensator_state(sc),
        inverter=np.zeros(1, dtype=INVERTER_STATE),
    )


def drive_derived(sc: Scenario, psi0: float, mh: dict) -> dict:
    """Derived quantities of the drive for ``summary.json`` (flux, limits, machine)."""
    m = sc.machine
    return {
        "flux_ref_Wb": psi0,
        "torque_constant_Nm_per_A": 1.5 * m.pole_pairs * mh["M_hat"] / mh["L2_hat"] * psi0,
        "current_limit_A": current_limit(sc),
        "divergence_current_A": divergence_current(sc),
        "rated_current_A": m.rated_current_A,
        "sigma": m.sigma,
        "T2_s": m.T2_s,
        "v_max_V": sc.inverter.v_max_V,
    }
