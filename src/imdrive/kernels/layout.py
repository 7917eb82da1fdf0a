"""Index layout of the flat arrays the compiled kernels work on.

The kernels never see Python objects: a drive is described by

* ``par``   float64[N_PAR]            — every scalar parameter (plant, inverter, controller, ...)
* ``prof_t``, ``prof_v`` float64[N_PROF, K], ``prof_n`` int64[N_PROF]
                                      — piecewise-linear time profiles (see :mod:`imdrive.profiles`)
* ``x``     float64[NX]               — continuous plant state
* ``c``     float64[NC]               — discrete controller / estimator state
* ``table`` float64[13, 13]           — fuzzy lookup table of the R2 compensator

The Python layer (:mod:`imdrive.scenario`) fills these from frozen dataclasses. Numba treats
module-level integers as compile-time constants, so named indices cost nothing.
Append new entries at the end of a block; never renumber within a release.
"""

# --------------------------------------------------------------------------------------------
# par: scalar parameters
# plant (true machine)
P_R1 = 0  # stator resistance at reference temperature, ohm
P_R2 = 1  # rotor resistance at reference temperature, ohm
P_LL1 = 2  # stator leakage inductance, H
P_LL2 = 3  # rotor leakage inductance, H
P_M = 4  # magnetising inductance, H
P_NP = 5  # pole pairs
P_J = 6  # inertia, kg m^2
P_B = 7  # viscous friction of the machine, N m s/rad
P_LOAD_VISC = 8  # load torque coefficient on w_m, N m s/rad
P_LOAD_FAN = 9  # load torque coefficient on w_m*|w_m|, N m s^2/rad^2
P_ALPHA1 = 10  # temperature coefficient of R1, 1/K
P_ALPHA2 = 11  # temperature coefficient of R2, 1/K
P_THETA_REF = 12  # reference temperature of R1, R2, degC
P_THETA_AMB = 13  # ambient temperature, degC
P_RTH1 = 14  # stator thermal resistance, K/W
P_TAU1 = 15  # stator thermal time constant, s
P_RTH2 = 16  # rotor thermal resistance, K/W
P_TAU2 = 17  # rotor thermal time constant, s
P_THERMAL = 18  # 1.0: thermal model on, 0.0: off
P_MECH_MODE = 19  # 0: J dw/dt = Te - TL, 1: speed imposed by profile PR_SPEED_IMPOSED
# inverter
P_VDC = 20  # DC-link voltage, V
P_INV_MODEL = 21  # 0: average-value
# simulation
P_TS = 22  # control period, s
P_NSUB = 23  # RK4 sub-steps per control period
P_I_LIMIT_DIV = 24  # divergence bound on |i_s|, A
P_W_LIMIT_DIV = 25  # divergence bound on |w_m|, rad/s
# drive
P_DRIVE_MODE = 26  # 0: open-loop voltage, 1: indirect field-oriented control
P_SPEED_FB = 27  # 0: measured speed, 1: MRAS estimate
# controller's own machine model (estimates, hats)
P_R1_HAT = 28
P_R2_HAT0 = 29  # initial rotor-resistance estimate, ohm
P_LL1_HAT = 30
P_LL2_HAT = 31
P_M_HAT = 32
# field-oriented control
P_KP_W = 33  # speed PI proportional gain, A/(rad/s)
P_KI_W = 34  # speed PI integral gain, A/rad
P_KP_I = 35  # current PI proportional gain, V/A
P_KI_I = 36  # current PI integral gain, V/(A s)
P_I_MAX = 37  # stator current magnitude limit of the controller, A
P_DECOUPLE = 38  # 1.0: cross-coupling / back-emf feed-forward on
# MRAS
P_WC = 39  # cut-off of Schauder's low-pass integrator replacement, rad/s (0: pure integrator)
P_K1 = 40  # MRAS proportional gain, (rad/s)/Wb^2
P_K2 = 41  # MRAS integral gain, (rad/s^2)/Wb^2
# current sensor
P_I_OFFSET_A = 42  # DC offset added to measured i_alpha, A
P_I_OFFSET_B = 43  # DC offset added to measured i_beta, A
# fuzzy R2 compensator
P_COMP_ON = 44  # 1.0: compensator present
P_COMP_T_ON = 45  # time the compensator is enabled, s
P_COMP_N = 46  # compensator period in control periods
P_COMP_GE = 47  # scaling gain of E = e_d0, 1/Wb
P_COMP_GDE = 48  # scaling gain of DE = change of e_d0 per compensator period, 1/Wb
P_COMP_GCR = 49  # resistance change per output level, ohm
P_R2_HAT_MIN = 50  # clamp, ohm
P_R2_HAT_MAX = 51  # clamp, ohm
# flux-current injection (persistent excitation)
P_INJ_AMP = 52  # amplitude of the sinusoid added to id*, A
P_INJ_FREQ = 53  # its frequency, Hz
P_INJ_LPF = 54  # optional low-pass on the demodulated product, rad/s (0: none)
P_COMP_INPUT = 55  # 0: e_d0 (paper), 1: demodulated e_d0 (injection)
P_LOG_EVERY = 56  # logging decimation (control periods per logged row)
P_COMP_AVG = 57  # 1.0: the compensator input is the mean over its period, 0.0: a sample
P_INJ_T_ON = 58  # time the injection starts, s
N_PAR = 64

# --------------------------------------------------------------------------------------------
# profile slots: piecewise-linear functions of time
PR_SPEED_REF = 0  # speed reference, mechanical rad/s
PR_LOAD = 1  # time-dependent part of the load torque, N m
PR_R1_SCALE = 2  # plant R1 multiplier (1 = reference value)
PR_R2_SCALE = 3  # plant R2 multiplier
PR_V_AMP = 4  # open-loop voltage: space-vector amplitude (= phase peak), V
PR_FREQ = 5  # open-loop voltage: frequency, Hz
PR_SPEED_IMPOSED = 6  # imposed mechanical speed when P_MECH_MODE = 1, rad/s
PR_FLUX_REF = 7  # rotor-flux reference, Wb
N_PROF = 8

# --------------------------------------------------------------------------------------------
# x: continuous plant state. Flux linkages are the electrical states: the equations are then
# linear in the state for a given speed, resistances enter only as coefficients (so R1, R2 may
# jump without discontinuity of the state), and the magnetic energy is a function of state.
X_PSI_S_A = 0  # stator flux linkage, alpha, Wb
X_PSI_S_B = 1
X_PSI_R_A = 2  # rotor flux linkage (stator-referred), alpha, Wb
X_PSI_R_B = 3
X_W_M = 4  # mechanical speed, rad/s
X_THETA_M = 5  # mechanical angle, rad
X_TH1 = 6  # stator winding temperature, degC
X_TH2 = 7  # rotor winding temperature, degC
X_E_IN = 8  # electrical input energy, J
X_E_CU = 9  # copper losses, J
X_E_EM = 10  # air-gap (electromechanical) work, integral of Te*w_m, J
X_E_LOAD = 11  # work done on the load and friction, J
NX = 12

# --------------------------------------------------------------------------------------------
# c: discrete controller/estimator state
C_THETA_E = 0  # field angle of the controller's synchronous frame, rad
C_INT_W = 1  # speed PI integral state, A
C_INT_D = 2  # d-axis current PI integral state, V
C_INT_Q = 3  # q-axis current PI integral state, V
C_V_PREV_A = 4  # voltage applied during the last period, alpha, V
C_V_PREV_B = 5
C_I_PREV_A = 6  # current measured at the last sample, alpha, A
C_I_PREV_B = 7
C_LAM_V_A = 8  # MRAS reference (voltage) model rotor flux, filtered, Wb
C_LAM_V_B = 9
C_LAM_I_A = 10  # MRAS adjustable (current) model rotor flux, unfiltered, Wb
C_LAM_I_B = 11
C_LAM_F_A = 12  # adjustable model passed through the same filter, Wb
C_LAM_F_B = 13
C_INT_E = 14  # integral of the MRAS error signal, Wb^2 s
C_W_HAT = 15  # MRAS speed estimate, electrical rad/s
C_R2_HAT = 16  # rotor-resistance estimate, ohm
C_E_D0 = 17  # flux error in the synchronous frame, d, Wb
C_E_Q0 = 18
C_E_D0_PREV = 19  # compensator input at its last sample
C_THETA_OL = 20  # angle of the open-loop voltage, rad
C_W_E = 21  # synchronous speed used by the controller, rad/s
C_ID_REF = 22
C_IQ_REF = 23
C_I_D = 24
C_I_Q = 25
C_INJ_PHASE = 26  # phase of the injected sinusoid, rad
C_DEMOD = 27  # demodulated, low-pass-filtered e_d0, Wb
C_CR = 28  # last compensator output level
C_COMP_STARTED = 29  # 1.0 once the compensator has taken its first sample
C_COMP_ACC = 30  # running sum of the compensator input over the current period, Wb
C_PSI_HAT = 31  # the IFOC's rotor-flux model, Wb
NC = 32

# --------------------------------------------------------------------------------------------
# logged signals (one row every P_LOG_EVERY control periods)
L_TIME = 0
L_W_M = 1
L_TE = 2
L_TL = 3
L_I_A = 4  # i_alpha, A
L_I_B = 5  # i_beta, A
L_PSI_R_A = 6
L_PSI_R_B = 7
L_V_A = 8  # applied voltage, alpha, V
L_V_B = 9
L_R1 = 10
L_R2 = 11
L_W_REF = 12  # mechanical rad/s
L_W_HAT = 13  # estimated mechanical speed, rad/s
L_ID_REF = 14
L_IQ_REF = 15
L_I_D = 16
L_I_Q = 17
L_R2_HAT = 18
L_E_D0 = 19
L_E_Q0 = 20
L_FLUX = 21  # |psi_r| of the plant, Wb
L_THETA_E = 22  # controller field angle, rad
L_TH1 = 23
L_TH2 = 24
L_DEMOD = 25
L_LAM_V_A = 26  # MRAS reference-model flux (filtered), Wb
L_LAM_V_B = 27
L_LAM_F_A = 28  # MRAS adjustable-model flux (filtered), Wb
L_LAM_F_B = 29
N_LOG = 30

# status codes returned by the engine
S_OK = 0
S_NAN = 1
S_CURRENT = 2
S_SPEED = 3
