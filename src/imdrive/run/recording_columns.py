"""The columns of a drive's recording and the rules a recording follows (what
:mod:`imdrive.run.recording` writes and :mod:`imdrive.run.recording_read` reads)."""

import math

#: column -> (unit, meaning); the unit is also the name's suffix
COLUMNS = {
    "time_s": ("s", "the sample t_k = k Ts: the start of control period k"),
    "i_a_meas_A": ("A", "measured stator current of phase a (from the measured alpha-beta)"),
    "i_b_meas_A": ("A", "phase b"),
    "i_c_meas_A": ("A", "phase c"),
    "i_alpha_meas_A": (
        "A",
        "measured stator current, alpha (amplitude-invariant Clarke; the estimator's i_ab)",
    ),
    "i_beta_meas_A": ("A", "measured stator current, beta"),
    "vdc_meas_V": ("V", "DC-link voltage as the controller measures it"),
    "v_alpha_cmd_V": (
        "V",
        "voltage the controller commanded at t_k for [t_k, t_k + Ts), "
        "less its inverter-error compensation: what it believes reaches the "
        "terminals, the estimator's voltage at the next sample; alpha",
    ),
    "v_beta_cmd_V": ("V", "the same, beta"),
    "speed_enc_rpm": ("rpm", "the rotor's mechanical speed at t_k (an ideal encoder)"),
    "i_inj_A": ("A", "the R2 compensator's injected d-axis current this period"),
    "speed_est_rpm": ("rpm", "the run's own speed estimate after this sample's step"),
    # context: the controller's values its estimator read at t_k
    "theta_e_rad": ("rad", "the controller's field angle at t_k"),
    "w_e_rad_s": ("rad/s", "the controller's stator frequency (electrical) the estimator read"),
    "id_ref_A": ("A", "the flux-current reference of the last period"),
    "iq_ref_A": ("A", "the torque-current reference of the last period"),
    "w_ref_rad_s": ("rad/s", "the speed reference (mechanical)"),
    "hold_R1_flag": ("1", "1 where the estimator's R1 adaptation was held"),
    "restart_flag": (
        "1",
        "1 where the drive's standstill R1 test set R1_hat at the last sample: the estimator "
        "restarts what it integrated through the test",
    ),
    "R1_hat_ohm": ("ohm", "the controller's R1_hat as the estimator read it"),
    "R2_hat_ohm": ("ohm", "the controller's R2_hat as the estimator read it"),
    "M_hat_H": ("H", "the controller's magnetising inductance as the estimator read it"),
    "R1_hat_after_ohm": ("ohm", "R1_hat right after the run's estimator's step"),
    "R2_hat_after_ohm": ("ohm", "R2_hat right after the run's estimator's step"),
    # what the R2 law reads of the controller besides (a replay runs the law on them)
    "t_hold_s": (
        "s",
        "the time the standstill R1 test held the duty cycle back (the R2 law runs in the "
        "duty cycle's time, t - t_hold)",
    ),
    "v_use_pu": ("pu", "the last commanded voltage over Vdc_meas/sqrt 3 (the voltage use)"),
    "k_flux_pu": ("pu", "the field weakening's flux factor (1: rated flux)"),
    "w_sl_rad_s": ("rad/s", "the controller's slip command of the last period (electrical)"),
    "iq_meas_A": (
        "A",
        "the torque current the controller measured at the last control period, in its frame",
    ),
    "w_fb_rad_s": (
        "rad/s",
        "the speed loop's feedback, mechanical: the drive's speed estimate (the encoder's on "
        "a sensored drive); the R2 law's gate watches the drive's transients with it",
    ),
    "L_inc_hat_H": (
        "H",
        "the controller's incremental magnetising inductance (its magnetising curve's slope "
        "at its flux; the injection's flux response)",
    ),
}

#: what a replay needs from every recording
REQUIRED = ("time_s", "i_alpha_meas_A", "i_beta_meas_A", "v_alpha_cmd_V", "v_beta_cmd_V")

#: a context column -> the value a replay takes where a recording lacks it (a number, or
#: the name of the column whose value it takes, itself perhaps defaulted)
CONTEXT_DEFAULTS = {
    "theta_e_rad": 0.0,  # the estimator's flux error then comes in the stationary frame
    "w_e_rad_s": 0.0,
    "id_ref_A": 0.0,
    "iq_ref_A": 0.0,
    "w_ref_rad_s": 0.0,
    "i_inj_A": 0.0,
    "hold_R1_flag": 1.0,  # an R1 law cannot tell regeneration without the references: held
    "restart_flag": 0.0,  # no standstill test told the estimator to restart
    "t_hold_s": 0.0,  # the R2 law in the recording's own time
    "v_use_pu": 0.0,  # no back-off of the injection, no voltage gate
    "k_flux_pu": 1.0,  # rated flux
    "w_sl_rad_s": 0.0,  # no slip decoupling of the detection
    "iq_meas_A": "iq_ref_A",  # (a column's name: that column's value) the thermal model's losses
    "L_inc_hat_H": 0.0,  # not recorded: the scenario's model keeps its own
    "w_fb_rad_s": math.nan,  # not recorded: the replayed estimate, or the encoder (sensored)
}

#: the model columns: all or none (with them the replayed model follows the controller's)
MODEL_COLUMNS = ("R1_hat_ohm", "R2_hat_ohm", "M_hat_H", "R1_hat_after_ohm", "R2_hat_after_ohm")

#: the sample period may vary by this much around its median
PERIOD_TOLERANCE = 0.01
