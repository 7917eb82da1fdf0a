"""From a :class:`~imdrive.config.scenario.Scenario` to the records the kernels run on.

Each block's record is filled by field name (:func:`imdrive.kernels.records.new_record`, which
refuses an unknown name) from the configuration and the gain design; the result is one
:class:`~imdrive.kernels.engine.DriveParams` and the initial
:class:`~imdrive.kernels.engine.DriveState`, every array of shape ``(1,)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from imdrive.config.profiles import Profile
from imdrive.config.scenario import Scenario
from imdrive.design.estimators import (
    afo_regeneration_gain,
    default_afo_gains,
    default_ekf_noise,
    default_reactive_mras_gains,
)
from imdrive.design.gains import default_current_gains, default_mras_gains, default_speed_gains
from imdrive.errors import ConfigError
from imdrive.fuzzy import fuzzy_table
from imdrive.kernels import profiles as kp
from imdrive.kernels.compensator import COMPENSATOR_PARAMS, COMPENSATOR_STATE
from imdrive.kernels.engine import (
    DRIVE_FOC,
    DRIVE_OPEN_LOOP,
    ESTIMATOR_CODES,
    LOG,
    SAMPLE_STATE,
    SIM_PARAMS,
    DriveParams,
    DriveState,
)
from imdrive.kernels.estimators.afo import AFO_PARAMS, AFO_STATE
from imdrive.kernels.estimators.ekf import EKF_PARAMS, EKF_STATE
from imdrive.kernels.estimators.mras import MRAS_PARAMS, MRAS_STATE
from imdrive.kernels.estimators.reactive_mras import REACTIVE_MRAS_PARAMS, REACTIVE_MRAS_STATE
from imdrive.kernels.ifoc import CONTROL_PARAMS, CONTROL_STATE
from imdrive.kernels.inverter import INVERTER_CODES, INVERTER_PARAMS, INVERTER_STATE
from imdrive.kernels.machine import PLANT_PARAMS, initial_plant_state, saturation_table
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.records import new_record
from imdrive.kernels.sensors import SENSOR_PARAMS
from imdrive.run._profiles import profiles_to_arrays

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm
MAX_LOG_BYTES = 2 * 2**30  # a log larger than this is refused before anything runs


def check_log_size(sc: Scenario) -> None:
    """Refuse a scenario whose log would not fit in :data:`MAX_LOG_BYTES`."""
    sim = sc.simulation
    log_bytes = (sim.n_steps // sim.log_every + 1) * LOG.itemsize
    if log_bytes > MAX_LOG_BYTES:
        raise ConfigError(
            "simulation.log_every",
            f"the log would take {log_bytes / 2**30:.1f} GiB (limit "
            f"{MAX_LOG_BYTES / 2**30:.0f} GiB): raise simulation.log_every",
        )


@dataclass
class DriveArrays:
    """Everything the compiled loop needs for one drive.

    Attributes
    ----------
    params : DriveParams
        Constant inputs, every array of shape ``(1,)`` (profiles and table with a leading 1).
    state0 : DriveState
        Initial state; :func:`copy_state` before running, the kernels update it in place.
    n_steps, log_every : int
    derived : dict
        Derived quantities reported in ``summary.json`` (gains, limits, ...).
    """

    params: DriveParams
    state0: DriveState
    n_steps: int
    log_every: int
    derived: dict

    @property
    def Ts(self) -> float:
        return float(self.params.sim["Ts"][0])


def copy_state(state: DriveState) -> DriveState:
    """A deep copy of a drive state (the kernels write into the arrays)."""
    return DriveState(*(a.copy() for a in state))


def _vf_profiles(sc: Scenario) -> tuple[Profile, Profile]:
    ol = sc.open_loop
    v_peak = ol.voltage_V.scaled(math.sqrt(2.0 / 3.0))
    if ol.vf_ramp_s > 0:
        T = ol.vf_ramp_s
        v_peak = Profile(((0.0, 0.0), (T, v_peak.final)))
        return v_peak, Profile(((0.0, 0.0), (T, ol.frequency_Hz.final)))
    return v_peak, ol.frequency_Hz


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


def _assumed_dead_time(sc: Scenario) -> float:
    """The dead time the controller's compensation assumes, s (default: the inverter's)."""
    t = sc.control.dead_time_compensation_s
    return sc.inverter.dead_time_s if t is None else t


#: The setting a derived quantity (summary.json "derived", or a record field) comes from, to
#: name it when the derived value overflows.
DERIVED_SOURCE = {
    "current_kp": "control.current_bandwidth_Hz",
    "current_ki": "control.current_bandwidth_Hz",
    "speed_kp": "control.speed_bandwidth_Hz",
    "speed_ki": "control.speed_bandwidth_Hz",
    "mras_K1": "mras.bandwidth_Hz",
    "mras_K2": "mras.bandwidth_Hz",
    "flux_ref_Wb": "control.flux_ref_Wb",
    "torque_constant_Nm_per_A": "control.flux_ref_Wb",
    "current_limit_A": "control.current_limit_A",
    "divergence_current_A": "simulation.divergence_current_A",
    "rated_current_A": "machine.rated_power_W",
    "sigma": "machine.M_H",
    "T2_s": "machine.R2_ohm",
    "v_max_V": "inverter.Vdc_V",
    "R2_hat_min_ohm": "compensator.R2_min_ohm",
    "R2_hat_max_ohm": "compensator.R2_max_ohm",
    "sim.w_lim": "simulation.divergence_speed_rpm",
    "sim.i_lim": "simulation.divergence_current_A",
    "control.v_max": "inverter.Vdc_V",
    "control.dtc_u": "control.dead_time_compensation_s",
    "plant.k_visc": "load.viscous_Nms",
    "plant.k_fan": "load.fan_Nms2",
    "sensor.adc_range": "sensor.adc_range_A",
    "comp.inj_amp": "injection.amplitude_A",
    "prof_v": "scenario",
}
_GAIN_OVERRIDE = {
    "current_kp": "control.current_kp",
    "current_ki": "control.current_ki",
    "speed_kp": "control.speed_kp",
    "speed_ki": "control.speed_ki",
    "mras_K1": "mras.K1",
    "mras_K2": "mras.K2",
}


def _not_finite(name: str, value, sc: Scenario) -> ConfigError:
    field = DERIVED_SOURCE.get(name, "scenario")
    if name in _GAIN_OVERRIDE:
        section, key = _GAIN_OVERRIDE[name].split(".")
        if getattr(getattr(sc, section), key) is not None:
            field = _GAIN_OVERRIDE[name]
    return ConfigError(
        field,
        f"gives a derived quantity {name} = {value} that is not a finite number (an overflow "
        "of extreme values): bring the settings it is computed from into a physical range",
    )


def check_finite(arrays: DriveArrays, sc: Scenario) -> None:
    """Refuse arrays holding a non-finite number: every derived quantity must be finite.

    Checks the reported derived quantities, then every float and complex field of the
    parameter and initial-state records and the profiles. Raises
    :class:`~imdrive.errors.ConfigError` naming the setting the first bad value comes from.
    """
    for name, value in arrays.derived.items():
        if not math.isfinite(float(value)):
            raise _not_finite(name, value, sc)
    for records in (arrays.params, arrays.state0):
        for rec_name, rec in zip(records._fields, records, strict=True):
            fields_ = rec.dtype.names or (None,)
            for f in fields_:
                arr = rec[f] if f is not None else rec
                if arr.dtype.kind in "fc" and not np.all(np.isfinite(arr)):
                    key = f"{rec_name}.{f}" if f is not None else rec_name
                    bad = arr[~np.isfinite(arr)].ravel()[0]
                    raise _not_finite(key, bad, sc)


def _estimator_records(sc: Scenario, Ts, psi0, R1h, R2h, Mh, L2h, sigma_L1):
    """The alternative estimators' parameter records (all filled; the engine runs the selected
    one) and their derived gains, each overridable in its section."""
    r2a = sc.estimator.R2_adaptation
    rm = sc.reactive_mras
    K1, K2 = default_reactive_mras_gains(psi0, L2h, 2 * math.pi * rm.bandwidth_Hz)
    K1 = rm.K1 if rm.K1 is not None else K1
    K2 = rm.K2 if rm.K2 is not None else K2
    rmras = new_record(REACTIVE_MRAS_PARAMS, K1=K1, K2=K2)

    af = sc.afo
    Kp, Ki, k_R1, k_R2 = default_afo_gains(
        psi0,
        R1h,
        R2h,
        sigma_L1,
        Mh,
        L2h,
        af.g1_per_s,
        2 * math.pi * af.bandwidth_Hz,
        af.R1_bandwidth_rad_s,
        af.R2_bandwidth_rad_s,
        sc.flux_injection.amplitude,
        2 * math.pi * sc.flux_injection.frequency_Hz,
    )
    regen = af.gain == "regeneration"
    g2 = afo_regeneration_gain(R1h, sigma_L1, Mh, L2h, af.g1_per_s, af.rho) if regen else af.g2_ohm
    afo = new_record(
        AFO_PARAMS,
        gain_mode=1 if regen else 0,
        rho=af.rho,
        g1=af.g1_per_s,
        g2=af.g2_ohm,
        Kp=af.Kp if af.Kp is not None else Kp,
        Ki=af.Ki if af.Ki is not None else Ki,
        k_R1=k_R1 if af.R1_adaptation else 0.0,
        k_R2=k_R2 if r2a == "afo" else 0.0,
        R_min=0.5,
        R_max=2.0,
    )

    ek = sc.ekf
    q, r, p0 = default_ekf_noise(
        Ts,
        sigma_L1,
        psi0,
        R2h,
        ek.voltage_noise_V,
        ek.flux_noise_Wb_per_s,
        ek.acceleration_noise_rad_s2,
        ek.R2_drift_ohm_per_s,
        ek.current_noise_A,
    )
    ekf = new_record(
        EKF_PARAMS,
        q=q,
        r=r,
        p0=p0,
        estimate_R2=r2a == "ekf",
        R2_min=0.5 * R2h,
        R2_max=2.0 * R2h,
        write_R2=r2a == "ekf",
    )
    derived = {
        "reactive_mras_K1": float(rmras["K1"][0]),
        "reactive_mras_K2": float(rmras["K2"][0]),
        "afo_Kp": float(afo["Kp"][0]),
        "afo_Ki": float(afo["Ki"][0]),
        "afo_g1_per_s": af.g1_per_s,
        "afo_g2_ohm": g2,
    }
    return {"rmras": rmras, "afo": afo, "ekf": ekf}, derived


def build_arrays(sc: Scenario) -> DriveArrays:
    """Fill every block's parameter and state records from the scenario.

    Every derived quantity is checked: a scenario whose derived parameters overflow (to
    infinity, NaN, or beyond a 64-bit integer) raises :class:`~imdrive.errors.ConfigError`
    naming the setting, before anything runs (:func:`check_finite`).
    """
    try:
        arrays = _build_arrays(sc)
    except ConfigError:
        raise
    except (ArithmeticError, ValueError) as exc:  # overflow of a float or of an int64 field
        raise ConfigError(
            "scenario",
            f"its derived parameters cannot be computed ({type(exc).__name__}: {exc}): some "
            "values are far outside a physical range",
        ) from None
    check_finite(arrays, sc)
    return arrays


def _build_arrays(sc: Scenario) -> DriveArrays:
    check_log_size(sc)
    m = sc.machine
    est = sc.estimator
    ctl = sc.control
    th = sc.plant.thermal
    Ts = sc.simulation.Ts_s
    i_div = sc.simulation.divergence_current_A or 100.0 * m.rated_current_A

    plant = new_record(
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
    sim = new_record(
        SIM_PARAMS,
        Ts=Ts,
        nsub=sc.simulation.substeps,
        i_lim=i_div,
        w_lim=sc.simulation.divergence_speed_rpm * RPM,
        mode=DRIVE_FOC if sc.drive.mode == "vector" else DRIVE_OPEN_LOOP,
        sensorless=ctl.speed_feedback != "measured",
        delay=ctl.delay_periods,
        estimator=ESTIMATOR_CODES.get(ctl.speed_feedback, 0),
        flux_inj_amp=sc.flux_injection.amplitude,
        flux_inj_freq=sc.flux_injection.frequency_Hz,
    )
    inv = sc.inverter
    inverter = new_record(
        INVERTER_PARAMS,
        Vdc=inv.Vdc_V,
        model=INVERTER_CODES[inv.model],
        t_d=inv.dead_time_s,
        v_drop=inv.device_drop_V,
        i_band=inv.sign_band_A,
        f_sw=inv.switching_frequency_Hz,
    )
    sen = sc.sensor
    sensor = new_record(
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
    Vdc_meas = sen.vdc_gain * inv.Vdc_V

    # the controller's own machine model
    R1h = est.R1_ohm if est.R1_ohm is not None else m.R1_ohm
    R2h = est.R2_ohm if est.R2_ohm is not None else m.R2_ohm
    Ll1h = est.Ll1_H if est.Ll1_H is not None else m.Ll1_H
    Ll2h = est.Ll2_H if est.Ll2_H is not None else m.Ll2_H
    Mh = est.M_H if est.M_H is not None else m.M_H
    model = new_record(MODEL_STATE, R1_hat=R1h, R2_hat=R2h, Ll1_hat=Ll1h, Ll2_hat=Ll2h, M_hat=Mh)

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
    control = new_record(
        CONTROL_PARAMS,
        n_p=m.pole_pairs,
        kp_w=gains["speed_kp"],
        ki_w=gains["speed_ki"],
        kp_i=gains["current_kp"],
        ki_i=gains["current_ki"],
        i_max=i_max,
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
    mras = new_record(
        MRAS_PARAMS,
        wc=sc.mras.wc_rad_s,
        K1=gains["mras_K1"],
        K2=gains["mras_K2"],
        k_R1=sc.mras.R1_rate_per_s,
        R1_fmax=sc.mras.R1_max_freq_Hz,
        R1_min=0.5 * R1h,
        R1_max=2.0 * R1h,
        psi2_norm=psi0 * psi0 if _mras_normalise(sc) else 0.0,
        R1_dc=sc.mras.R1_standstill,
        # the flux build-up: four rotor time constants of the controller's model
        R1_dc_settle=4.0 * L2h / R2h,
    )

    est_params, est_derived = _estimator_records(sc, Ts, psi0, R1h, R2h, Mh, L2h, sigma_L1)
    gains.update(est_derived)

    comp = sc.compensator
    inj = sc.injection
    if comp.period_s is not None:
        comp_period = comp.period_s
    elif comp.input == "demodulated":
        comp_period = 1.0 / inj.frequency_Hz
    else:
        comp_period = 0.01
    n_comp = max(int(round(comp_period / Ts)), 1)
    f3 = inj.frequency3_Hz
    if f3 is not None and comp.enabled and inj.amplitude_A > 0.0:
        cycles = n_comp * Ts * f3
        if abs(cycles - round(cycles)) > 1e-6 * max(cycles, 1.0):
            raise ConfigError(
                "injection.frequency3_Hz",
                f"the compensator period ({n_comp * Ts:g} s) must hold a whole number of its "
                f"periods (got {cycles:g})",
            )
    R2_min = comp.R2_min_ohm if comp.R2_min_ohm is not None else 0.5 * R2h
    R2_max = comp.R2_max_ohm if comp.R2_max_ohm is not None else 2.0 * R2h
    compensator = new_record(
        COMPENSATOR_PARAMS,
        enabled=comp.enabled,
        t_on=comp.t_on_s,
        n=n_comp,
        G_E=comp.gain_E_per_Wb,
        G_DE=comp.gain_DE_per_Wb,
        G_CR=comp.G_CR_ohm,
        R2_min=R2_min,
        R2_max=R2_max,
        demodulated=comp.input == "demodulated",
        average=comp.average,
        inj_amp=inj.amplitude_A,
        inj_freq=inj.frequency_Hz,
        inj_lpf=inj.lowpass_rad_s,
        inj_t_on=inj.t_on_s,
        inj_hp_wc=sc.mras.wc_rad_s if inj.compensate_filter else 0.0,
        **_gating(sc),
    )
    table = fuzzy_table(comp.table).astype(np.float64)

    v_amp, freq = _vf_profiles(sc)
    profiles = [Profile.constant(0.0)] * kp.N_PROF
    profiles[kp.PR_SPEED_REF] = ctl.speed_ref_rpm.scaled(RPM)
    profiles[kp.PR_LOAD] = sc.load.torque_Nm
    profiles[kp.PR_R1_SCALE] = sc.plant.R1_scale
    profiles[kp.PR_R2_SCALE] = sc.plant.R2_scale
    profiles[kp.PR_V_AMP] = v_amp
    profiles[kp.PR_FREQ] = freq
    profiles[kp.PR_SPEED_IMPOSED] = sc.plant.imposed_speed_rpm.scaled(RPM)
    profiles[kp.PR_FLUX_REF] = flux_ref
    prof_t, prof_v, prof_n = profiles_to_arrays(profiles)

    w_m0 = profiles[kp.PR_SPEED_IMPOSED](0.0) if sc.plant.speed_mode == "imposed" else 0.0
    params = DriveParams(
        sim=sim,
        plant=plant,
        inverter=inverter,
        sensor=sensor,
        control=control,
        mras=mras,
        comp=compensator,
        **est_params,
        prof_t=prof_t[None],
        prof_v=prof_v[None],
        prof_n=prof_n[None],
        tables=np.ascontiguousarray(table[None]),
        table_idx=np.zeros(1, dtype=np.int64),
    )
    state0 = DriveState(
        plant=initial_plant_state(th.theta_init_C, w_m0),
        sample=np.zeros(1, dtype=SAMPLE_STATE),
        model=model,
        control=np.zeros(1, dtype=CONTROL_STATE),
        mras=np.zeros(1, dtype=MRAS_STATE),
        comp=_compensator_state(sc),
        inverter=np.zeros(1, dtype=INVERTER_STATE),
        rmras=np.zeros(1, dtype=REACTIVE_MRAS_STATE),
        afo=np.zeros(1, dtype=AFO_STATE),
        ekf=np.zeros(1, dtype=EKF_STATE),
    )

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
            "R2_hat_min_ohm": R2_min,
            "R2_hat_max_ohm": R2_max,
        }
    )
    return DriveArrays(
        params=params,
        state0=state0,
        n_steps=sc.simulation.n_steps,
        log_every=sc.simulation.log_every,
        derived=derived,
    )


def _gating(sc) -> dict:
    """The compensator's gating, frequency-schedule and step-law parameters (issue 10; off:
    zeros)."""
    comp = sc.compensator
    on = comp.gating if comp.gating is not None else comp.input == "demodulated"
    out = {}
    inj = sc.injection
    headroom = inj.headroom if inj.headroom is not None else sc.control.field_weakening
    if headroom and inj.amplitude_A > 0.0:
        if not inj.headroom_from < inj.headroom_to:
            raise ConfigError("injection.headroom_from", "must be < injection.headroom_to")
        out["inj_v_lo"] = inj.headroom_from
        out["inj_v_hi"] = inj.headroom_to
    if comp.step_law == "adaptive":
        dmax = comp.drift_max_ohm if comp.drift_max_ohm is not None else 3.0 * comp.G_CR_ohm
        out |= {
            "fine": True,
            "fine_gain": comp.fine_gain,
            "drift_gain": comp.drift_gain,
            "drift_max": dmax,
            "drift_fmin": _drift_fmin(sc),
        }
    if not (on and comp.enabled):
        return out
    f2 = sc.injection.frequency2_Hz
    if f2 is None:
        f2 = 2.0 * sc.injection.frequency_Hz
    return out | {
        "gate": True,
        "gate_dw": comp.gate_speed_rpm * RPM,
        "gate_diq": comp.gate_iq_A,
        "gate_v": comp.gate_voltage,
        "gate_df": comp.gate_band_Hz if sc.injection.amplitude_A > 0.0 else 0.0,
        "gate_hold": float(comp.gate_hold_periods),
        "inj_freq2": f2 if sc.injection.amplitude_A > 0.0 and comp.gate_band_Hz > 0 else 0.0,
        "inj_freq3": (
            sc.injection.frequency3_Hz
            if sc.injection.frequency3_Hz is not None
            and sc.injection.amplitude_A > 0.0
            and comp.gate_band_Hz > 0
            else 0.0
        ),
    }


def _mras_normalise(sc) -> bool:
    """Whether the MRAS error is normalised by the flux magnitude (mras.normalise)."""
    if sc.mras.normalise is not None:
        return sc.mras.normalise
    return sc.control.field_weakening


def _drift_fmin(sc) -> float:
    """Stator frequency below which the adaptive law has no drift term, Hz (0: never)."""
    comp = sc.compensator
    if comp.drift_min_freq_Hz is not None:
        return comp.drift_min_freq_Hz
    if sc.injection.amplitude_A <= 0.0:
        return 0.0
    f2 = sc.injection.frequency2_Hz
    return max(sc.injection.frequency_Hz, f2 if f2 is not None else 2 * sc.injection.frequency_Hz)


def _compensator_state(sc) -> np.ndarray:
    """Initial COMPENSATOR_STATE: zeros (no previous iq* yet), the injection frequency in use."""
    st = np.zeros(1, dtype=COMPENSATOR_STATE)
    st[0]["inj_f"] = sc.injection.frequency_Hz
    st[0]["inj_f_prev"] = sc.injection.frequency_Hz
    return st
