"""One builder per block: its record's fields from the scenario, by field name.

Each ``*_fields`` function turns the settings of one block into the fields of its record, with
the gain design where the block has one; :func:`drive_records` makes every block's record
(``(1,)`` arrays of the block's dtype, :func:`imdrive.kernels.records.new_records`) in one go.
Every machine-dependent value comes from the one resolver: a setting whose unset value
depends on the scenario from :func:`imdrive.config.defaults.in_effect` (what ``imdrive show
--all`` and ``summary.json`` print for it), a per-unit pair from the scenario's resolved
values ``D`` (:func:`imdrive.config.perunit.resolve`, computed once per scenario, which the
resolver reads too). Two builders keep their own module: the standstill R1 test's record
(:func:`imdrive.config.r1_standstill.r1_standstill_fields`) and the drive's sequencing
(:func:`imdrive.config.sequence.sequence`), each a set of record fields rather than one
setting's default.
:func:`imdrive.run.build.build_arrays` assembles the drive; the estimator's records come from
its own builder (:mod:`imdrive.run.estimators`).
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.config.commissioning_ideal import current_gain_b_per_a
from imdrive.config.controller_model import inverter_error_half, magnetising_table
from imdrive.config.defaults import in_effect
from imdrive.config.perunit import Resolved
from imdrive.config.profiles import Profile
from imdrive.config.r1_standstill import r1_standstill_fields
from imdrive.config.scenario import Scenario
from imdrive.config.sequence import sequence
from imdrive.design.gains import default_current_gains, default_speed_gains, torque_constant
from imdrive.kernels import profiles as kp
from imdrive.kernels.compensator import COMPENSATOR_PARAMS, COMPENSATOR_STATE
from imdrive.kernels.engine import DRIVE_FOC, DRIVE_OPEN_LOOP, SAMPLE_STATE, SIM_PARAMS, DriveState
from imdrive.kernels.ifoc import CONTROL_PARAMS, CONTROL_STATE
from imdrive.kernels.inverter import INVERTER_CODES, INVERTER_PARAMS, INVERTER_STATE
from imdrive.kernels.machine import PLANT_PARAMS, initial_plant_state, saturation_table
from imdrive.kernels.model import MODEL_STATE, MODEL_TABLE_POINTS
from imdrive.kernels.r2_law_registry import compensator_dtypes
from imdrive.kernels.records import new_records
from imdrive.kernels.sensors import SENSOR_PARAMS
from imdrive.run._profiles import profiles_to_arrays
from imdrive.run.compensator_blocks import (  # noqa: F401  (re-exported: old paths)
    compensator_fields,
    fuzzy_lookup_table,
    gives_flux_error,
    headroom_rate_per_s,
    law_slot,
)

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm


def saturation_curve(sc: Scenario, D: Resolved | None = None) -> dict:
    """The plant's magnetising-curve fields (see ``SaturationSettings``); ``D``: the scenario's
    resolved per-unit values, when known (they hold the curve)."""
    sat = sc.plant.saturation
    m = sc.machine
    Lm0, psi_sat, S = sat.curve(m) if D is None else D.sat_curve
    fields = {"saturation": sat.enabled, "Lm0": Lm0, "psi_sat": psi_sat, "S": S}
    if sat.enabled:  # the inverse curve tabulated once per run (no Newton loop per step)
        table = saturation_table(m.Ll1_H, m.Ll2_H, Lm0, psi_sat, S)
        table.pop("sat_table_error")
        fields.update(table)
    return fields


def plant_fields(sc: Scenario, D: Resolved) -> dict:
    """``PLANT_PARAMS``: the machine, its load, thermal model and saturation."""
    m = sc.machine
    th = sc.plant.thermal
    # off, the kernels never read them (kernels/machine.py, bridge.py: if p.thermal)
    Rth1, Rth2 = (
        (in_effect(sc, "plant.thermal.Rth1_K_per_W"), in_effect(sc, "plant.thermal.Rth2_K_per_W"))
        if th.enabled
        else (0.0, 0.0)
    )
    return dict(
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
        Rth1=Rth1,
        tau1=th.tau1_s,
        Rth2=Rth2,
        tau2=th.tau2_s,
        thermal=th.enabled,
        speed_imposed=sc.plant.speed_mode == "imposed",
        **saturation_curve(sc, D),
    )


def divergence_current(sc: Scenario, D: Resolved) -> float:
    """The current beyond which a run counts as diverged, A
    (``simulation.divergence_current_A``: :mod:`imdrive.config.defaults`)."""
    return in_effect(sc, "simulation.divergence_current_A")


def sim_fields(sc: Scenario, D: Resolved) -> dict:
    """``SIM_PARAMS``: the loop's period, sub-steps, divergence bounds and mode."""
    ctl = sc.control
    return dict(
        Ts=sc.simulation.Ts_s,
        nsub=sc.simulation.substeps,
        i_lim=divergence_current(sc, D),
        w_lim=in_effect(sc, "simulation.divergence_speed_rpm") * RPM,
        mode=DRIVE_FOC if sc.drive.mode == "vector" else DRIVE_OPEN_LOOP,
        sensorless=ctl.speed_feedback != "measured",
        delay=ctl.delay_periods,
        flux_inj_amp=sc.flux_injection.amplitude,
        flux_inj_freq=in_effect(sc, "flux_injection.frequency_Hz"),
    )


def inverter_fields(sc: Scenario) -> dict:
    """``INVERTER_PARAMS``: DC link, model, dead time, device drop, switching frequency."""
    inv = sc.inverter
    return dict(
        Vdc=inv.Vdc_V,
        model=INVERTER_CODES[inv.model],
        t_d=inv.dead_time_s,
        v_drop=inv.device_drop_V,
        i_band=in_effect(sc, "inverter.sign_band_A"),
        f_sw=inv.switching_frequency_Hz,
    )


def sensor_fields(sc: Scenario) -> dict:
    """``SENSOR_PARAMS``: current sensors (offsets, gains, noise, ADC), the DC-link gain and
    the controller's calibration of phase b (``controller_model.current_gain_b_per_a``)."""
    sen = sc.sensor
    # both readings to the gains' geometric mean: the relative error goes, the common one
    # (which the drive cannot know) stays what the two sensors had on average
    ratio = current_gain_b_per_a(sc)
    cal_a, cal_b = math.sqrt(ratio) - 1.0, 1.0 / math.sqrt(ratio) - 1.0
    return dict(
        i_offset_ab=complex(sen.i_offset_alpha_A, sen.i_offset_beta_A),
        phase_model=sen.per_phase or ratio != 1.0,  # a calibration applies per phase
        gain_a=sen.gain_a,
        gain_b=sen.gain_b,
        offset_a=sen.offset_a_A,
        offset_b=sen.offset_b_A,
        noise_rms=sen.noise_rms_A,
        adc_bits=sen.adc_bits or 0,
        adc_range=in_effect(sc, "sensor.adc_range_A"),
        seed=sen.seed,
        vdc_gain=sen.vdc_gain,
        cal_a=cal_a,
        cal_b=cal_b,
    )


def model_fields(sc: Scenario, D: Resolved) -> tuple[dict, dict]:
    """``MODEL_STATE`` (the controller's machine model: its estimates, absolute or as ratios of
    the plant's, :func:`imdrive.config.perunit.resolve`; unset: the plant's) and the
    model's inductances ``R1_hat, R2_hat, M_hat, L1_hat, L2_hat, sigma_L1_hat`` as a dict."""
    R1h, R2h, Ll1h, Ll2h, Mh = (
        in_effect(sc, f"estimator.{key}") for key in ("R1_ohm", "R2_ohm", "Ll1_H", "Ll2_H", "M_H")
    )
    model = dict(R1_hat=R1h, R1_gate=R1h, R2_hat=R2h, Ll1_hat=Ll1h, Ll2_hat=Ll2h, M_hat=Mh)
    cm = sc.controller_model
    if D.model_curve:  # the saturation-aware flux model (kernels/model.py)
        psi, i_m, di_m = magnetising_table(cm.magnetising_psi_Wb, cm.magnetising_Lm_H)
        model["sat_n"] = len(psi)
        model["sat_psi"] = _padded(psi)
        model["sat_im"] = _padded(i_m)
        model["sat_dim"] = _padded(di_m)
        model["sat_Lm0"] = cm.magnetising_Lm_H[0]
        model["L_inc_hat"] = Mh
    L1h, L2h = Ll1h + Mh, Ll2h + Mh
    sigma_L1 = L1h - Mh**2 / L2h
    mh = dict(R1_hat=R1h, R2_hat=R2h, M_hat=Mh, L1_hat=L1h, L2_hat=L2h, sigma_L1_hat=sigma_L1)
    return model, mh


def _padded(values) -> np.ndarray:
    """A table's nodes in the kernels' fixed-size array, the last value repeated after them."""
    out = np.full(MODEL_TABLE_POINTS, float(values[-1]))
    out[: len(values)] = values
    return out


def flux_reference(sc: Scenario) -> Profile:
    """The rotor-flux reference profile, Wb (default: the machine's rated flux)."""
    return sc.control.flux_ref_Wb or Profile.constant(in_effect(sc, "control.flux_ref_Wb"))


def initial_flux(sc: Scenario, D: Resolved) -> float:
    """The rotor-flux reference at t = 0, Wb (that of :func:`flux_reference`)."""
    return in_effect(sc, "control.flux_ref_Wb")


#: The orientation check (kernels/ifoc.py ``check_orientation``) runs from this stator
#: frequency, per-unit of the rated one (the back-emf then dominates the stator voltage) ...
ORIENTATION_FROM_PU = 0.5
#: ... and realigns after the frame has been seen this long more than 60 degrees off, s
ORIENTATION_TRIP_S = 0.05
#: The frame follows the speed estimator's own rotor-flux estimate, where it gives one (the
#: observer, the EKF), from this stator frequency, per-unit of the rated one
#: (kernels/ifoc.py, direct field orientation). Measured: from 0 (everywhere) the observer's
#: R2 tracking converged in 42 of the zero-frequency study's 84 runs instead of 51 and the EKF
#: on the realistic drive ended 7.0 rpm off at 70 rpm regenerating the rated torque instead of
#: 2.9 (near zero stator frequency the observer's flux is its voltage model, with R1's and the
#: inverter's errors); from 0.1 neither moves, and the machine envelope gains the same 8 runs
#: (Krause 2250 hp at rated speed regenerating, lost by both observer drives with the
#: integrated slip).
DIRECT_ORIENTATION_FROM_PU = 0.1


def _r1_settle_s(D: Resolved) -> float:
    """How long the online R1 law stays held after the speed reference last moved, s: three
    rotor time constants of the estimate (the flux error a transient leaves) plus three time
    constants of the speed loop."""
    return 3.0 * D.T2_s + 3.0 / (2 * math.pi * D.speed_bandwidth_Hz)


def control_fields(sc: Scenario, D: Resolved, mh: dict, psi0: float) -> tuple[dict, dict]:
    """``CONTROL_PARAMS`` and the controller's gains (current and speed PI from bandwidths,
    each overridable), from the model ``mh`` of :func:`model_fields` and flux ``psi0``."""
    m = sc.machine
    ctl = sc.control
    inv = sc.inverter
    Vdc_meas = sc.sensor.vdc_gain * inv.Vdc_V
    R_sigma = mh["R1_hat"] + (mh["M_hat"] / mh["L2_hat"]) ** 2 * mh["R2_hat"]
    k_t = torque_constant(m.pole_pairs, mh["M_hat"], mh["L2_hat"], psi0)
    kp_i, ki_i = default_current_gains(
        mh["sigma_L1_hat"], R_sigma, 2 * math.pi * ctl.current_bandwidth_Hz
    )
    R_a = 0.0
    imc = in_effect(sc, "control.current_controller") == "imc"
    if imc:  # internal model control, kernels/current_control.py
        R_a = max(kp_i - R_sigma, 0.0)
        ki_i = 2 * math.pi * ctl.current_bandwidth_Hz * (R_sigma + R_a)
    a_s = 2 * math.pi * in_effect(sc, "control.speed_bandwidth_Hz")
    kp_w, ki_w = default_speed_gains(m.J_kgm2, k_t, a_s)
    ie_rate = in_effect(sc, "control.inverter_error_adaptation_per_s")
    gains = {
        "current_kp": ctl.current_kp if ctl.current_kp is not None else kp_i,
        "current_ki": ctl.current_ki if ctl.current_ki is not None else ki_i,
        "speed_kp": ctl.speed_kp if ctl.speed_kp is not None else kp_w,
        "speed_ki": ctl.speed_ki if ctl.speed_ki is not None else ki_w,
    }
    control = dict(
        n_p=m.pole_pairs,
        kp_w=gains["speed_kp"],
        ki_w=gains["speed_ki"],
        kp_i=gains["current_kp"],
        ki_i=gains["current_ki"],
        i_max=current_limit(sc, D),
        v_max=Vdc_meas / math.sqrt(3.0),
        decouple=ctl.decoupling,
        dec_meas=imc,
        R_a=R_a,
        angle_advance=0.5 + (ctl.delay_periods if ctl.delay_compensation else 0),
        dtc_u=(
            in_effect(sc, "control.dead_time_compensation_s")
            * inv.switching_frequency_Hz
            * Vdc_meas
            if ctl.dead_time_compensation == "feedforward"
            else 0.0
        ),
        dtc_band=in_effect(sc, "inverter.sign_band_A"),
        # the switching bridge's dead-time loss has the shape of the current's ripple at the
        # commutations; the compensation follows it (kernels/ifoc.py, commutation_ripple)
        dtc_ripple=(
            Vdc_meas * sc.simulation.Ts_s / mh["sigma_L1_hat"]
            if inv.model == "switching" and ctl.dead_time_compensation_band == "ripple"
            else 0.0
        ),
        ie_rate=ie_rate,
        ie_wc=2 * math.pi * ctl.current_bandwidth_Hz,
        ie_wmin=2 * math.pi * m.rated_frequency_Hz * ctl.inverter_error_adaptation_fmin_pu,
        # the standstill R1 identification absorbed the residual the scale learns
        ie_r1=ie_rate > 0 and sc.mras.R1_standstill,
        ie_veq=ctl.inverter_error_signal == "stator-voltage",
        fw=in_effect(sc, "control.field_weakening"),
        fw_v=ctl.field_weakening_voltage,
        fw_rate=ctl.field_weakening_rate,
        fw_min=ctl.field_weakening_min,
        fw_bound=ctl.field_weakening_bound,
        w_fw_sched=in_effect(sc, "control.speed_gain_flux_scaling"),
        r1_settle=_r1_settle_s(D),
        or_wmin=(
            2 * math.pi * m.rated_frequency_Hz * ORIENTATION_FROM_PU if ctl.reorientation else 0.0
        ),
        or_trip=ORIENTATION_TRIP_S,
        dfo_wmin=2 * math.pi * m.rated_frequency_Hz * DIRECT_ORIENTATION_FROM_PU,
        **r1_standstill_fields(sc, mh["R1_hat"], mh["L2_hat"] / mh["R2_hat"]),
    )
    cm = sc.controller_model
    if D.model_inverter_error:  # the identified inverter-error table replaces dtc_u
        ie_i, ie_u = inverter_error_half(cm.inverter_error_i_A, cm.inverter_error_u_V)
        control["ie_n"] = len(ie_i)
        control["ie_i"] = _padded(ie_i)
        control["ie_u"] = _padded(ie_u)
        control["dtc_u"] = 0.0
    return control, gains


def current_limit(sc: Scenario, D: Resolved) -> float:
    """The controller's current limit, A (``control.current_limit_A``:
    :mod:`imdrive.config.defaults`)."""
    return in_effect(sc, "control.current_limit_A")


def _vf_profiles(sc: Scenario) -> tuple[Profile, Profile]:
    ol = sc.open_loop
    v_peak = ol.voltage_V.scaled(math.sqrt(2.0 / 3.0))
    if ol.vf_ramp_s > 0:
        T = ol.vf_ramp_s
        v_peak = Profile(((0.0, 0.0), (T, v_peak.final)))
        return v_peak, Profile(((0.0, 0.0), (T, ol.frequency_Hz.final)))
    return v_peak, ol.frequency_Hz


def profile_list(sc: Scenario, D: Resolved | None = None) -> list[Profile]:
    """Every profile the kernels read, in the order of ``kernels/profiles.py`` (SI units);
    ``D``: the scenario's resolved per-unit values, when known (for the rated flux)."""
    v_amp, freq = _vf_profiles(sc)
    profiles = [Profile.constant(0.0)] * kp.N_PROF
    seq = sequence(sc)  # per-unit resolved, premagnetised, ramps at the torque limit
    profiles[kp.PR_SPEED_REF] = seq.speed_ref_rpm.scaled(RPM)
    profiles[kp.PR_LOAD] = seq.load_Nm
    profiles[kp.PR_R1_SCALE] = sc.plant.R1_scale
    profiles[kp.PR_R2_SCALE] = sc.plant.R2_scale
    profiles[kp.PR_V_AMP] = v_amp
    profiles[kp.PR_FREQ] = freq
    profiles[kp.PR_SPEED_IMPOSED] = sc.plant.imposed_speed_rpm.scaled(RPM)
    psi = sc.machine.rated_flux_Wb if D is None else D.psi_rated
    profiles[kp.PR_FLUX_REF] = sc.control.flux_ref_Wb or Profile.constant(psi)
    return profiles


def profile_arrays(sc: Scenario, D: Resolved | None = None):
    """The profiles as the kernels' breakpoint arrays ``(prof_t, prof_v, prof_n)``."""
    return profiles_to_arrays(profile_list(sc, D))


def _compensator_state(
    D: Resolved, dtype: np.dtype = COMPENSATOR_STATE, law_state: np.ndarray | None = None
) -> np.ndarray:
    """Initial COMPENSATOR_STATE (``dtype``: with a plug-in law's state in its ``law`` slot,
    ``law_state``): zeros (no previous iq* yet), the injection frequency in use."""
    st = np.zeros(1, dtype=dtype)
    if law_state is not None:
        st["law"] = law_state
    f1 = D.inj_f1
    st[0]["inj_f"] = f1
    st[0]["inj_f_prev"] = f1
    return st


def initial_state(
    sc: Scenario,
    D: Resolved,
    model: np.ndarray,
    est_state: np.ndarray,
    comp: np.ndarray | None = None,
) -> DriveState:
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
        comp=_compensator_state(D) if comp is None else comp,
        inverter=np.zeros(1, dtype=INVERTER_STATE),
    )


def drive_derived(sc: Scenario, D: Resolved, psi0: float, mh: dict) -> dict:
    """Derived quantities of the drive for ``summary.json`` (flux, limits, machine)."""
    m = sc.machine
    return {
        "flux_ref_Wb": psi0,
        "torque_constant_Nm_per_A": torque_constant(m.pole_pairs, mh["M_hat"], mh["L2_hat"], psi0),
        "current_limit_A": current_limit(sc, D),
        "divergence_current_A": divergence_current(sc, D),
        "rated_current_A": D.I_rated,
        "sigma": D.sigma,
        "T2_s": D.T2_s,
        "v_max_V": D.v_max_V,
    }


def drive_records(
    sc: Scenario, D: Resolved, model: dict, mh: dict, psi0: float
) -> tuple[dict, dict, dict]:
    """Every block's record but the estimator's, made in one go, and the derived quantities
    the blocks report (gains, compensator period and clamps).

    Parameters
    ----------
    sc : Scenario
        The scenario.
    D : Resolved
        Its per-unit values resolved (:func:`imdrive.config.perunit.resolve`).
    model, mh : dict
        The controller's model: its ``MODEL_STATE`` fields and inductances
        (:func:`model_fields`).
    psi0 : float
        The rotor-flux reference at t = 0, Wb.

    Returns
    -------
    records : dict
        ``{"sim", "plant", "inverter", "sensor", "control", "comp"}``: ``(1,)`` parameter
        records; ``"model"``: the controller's initial ``MODEL_STATE``.
    gains, comp_derived : dict
        The controller's gains; the compensator's period and clamps.
    """
    control, gains = control_fields(sc, D, mh, psi0)
    comp, comp_derived = compensator_fields(sc, D)
    law, law_params, law_state = law_slot(sc, D)
    comp_params, comp_state = compensator_dtypes(COMPENSATOR_PARAMS, COMPENSATOR_STATE, law)
    if law is not None:
        comp["law"] = law_params
    records = new_records(
        {
            "sim": (SIM_PARAMS, sim_fields(sc, D)),
            "plant": (PLANT_PARAMS, plant_fields(sc, D)),
            "inverter": (INVERTER_PARAMS, inverter_fields(sc)),
            "sensor": (SENSOR_PARAMS, sensor_fields(sc)),
            "control": (CONTROL_PARAMS, control),
            "comp": (comp_params, comp),
            "model": (MODEL_STATE, model),
        }
    )
    records["comp_state"] = _compensator_state(D, comp_state, law_state)
    return records, gains, comp_derived
