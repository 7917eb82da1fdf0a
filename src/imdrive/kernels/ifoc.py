"""Field-oriented (vector) control, indirect or direct on an observer's flux, and the
open-loop voltage drive.

Indirect field orientation (the paper's Fig. 4): the controller's synchronous frame has the angle

    theta_e = \\int (n_p w_fb + w_sl) dt,     w_sl = (M_hat / T2_hat) iq* / psi_hat,
    T2_hat d(psi_hat)/dt + psi_hat = M_hat id*,  T2_hat = L2_hat / R2_hat

where ``w_fb`` is the speed feedback (measured, or the MRAS estimate) and ``R2_hat`` the
*estimated* rotor resistance, so a wrong R2_hat shows up exactly where it does in a real drive.
In steady state ``psi_hat = M_hat id*`` and the slip is the paper's ``(R2_hat/L2_hat) iq*/id*``;
the flux model keeps the orientation right while the flux changes (magnetising, or the injected
sinusoid of the persistent-excitation compensator; the AC flux component for R2
identification is Kubota & Matsuse, IEEE Trans. Ind. Appl. 30(5), 1994).

**Direct field orientation on an observer's flux.** A speed estimator that observes the
rotor flux itself (the adaptive full-order observer, the EKF: ``flux`` in
:mod:`imdrive.kernels.estimators.registry`) sets the frame's angle to its flux estimate's
wherever the stator frequency is at least ``p.dfo_wmin`` (0.1 of the rated,
:data:`imdrive.run.blocks.DIRECT_ORIENTATION_FROM_PU`) and the estimate at least half the
reference flux: the scheme of Kubota, Matsuse & Nakano (IEEE Trans. Ind. Appl. 29(2), 1993),
whose observer's flux the vector control uses. There the observer's flux leans on the voltage
model and does not follow ``R2_hat``, while the integrated slip above does: an observer drive
from ``R2_hat(0) = 1.2 R2`` on Krause 2250 hp ran the ramp to the rated speed with the frame
up to 7 degrees off and the flux 12 % high (5.9 degrees with today's faster speed
adaptation), reached the voltage limit early and lost control at the ramp's end (both
observer drives, 8 runs of the machine envelope), and the EKF drive lost control on the
ramp; oriented on the observer's flux the frame stays within 1.7 degrees
(tests/drive/test_direct_orientation.py). Below that frequency the frame integrates the slip
from where the observer left it (the observer's flux is then the current model with
``R2_hat``, or near zero stator frequency its regeneration gain's voltage model, whose R1 and
inverter errors the integrated slip does not see).

The rotor-flux reference is expressed as the flux-current reference ``id* = psi* / M_hat`` (plus
an optional injected sinusoid); the speed PI gives a torque command, expressed as the q current
at the reference flux and divided by the flux model, ``iq* = u psi*/psi_hat``, so the torque
does not follow flux changes; synchronous-frame current PIs with
cross-coupling and back-emf feed-forward give the voltage, limited to the inverter's range.

Gain formulas (the defaults; each can be overridden in the scenario):

* current PI, pole-zero cancellation of the stator transient ``sigma L1 di/dt = v - R_sigma i``
  (``R_sigma = R1 + (M/L2)^2 R2``)::

      kp_i = sigma L1 a_c,   ki_i = R_sigma a_c            (closed loop ~ a_c / (s + a_c))

* speed PI, with ``k_t = 1.5 n_p (M/L2) psi*`` the torque constant (N m/A)::

      kp_w = J a_s / k_t,    ki_w = kp_w a_s / 4           (crossover ~ a_s, PI zero at a_s/4)
      (in field weakening times k and k^2 with w_fw_sched: kernels/speed_control.py)

Both PIs use back-calculation anti-windup: after saturation the integral state is corrected by
the part of the output that could not be applied, so the next output starts from the limit."""

from __future__ import annotations

import math

from imdrive.kernels.current_control import decoupling_voltage
from imdrive.kernels.features import has_feedforward
from imdrive.kernels.inverter import (
    clarke,
    duty_cycles,
    limit_magnitude,
    phase_values,
    smooth_sign,
)

# the online scale of the inverter-error compensation (imported here for the old paths)
from imdrive.kernels.inverter_scale import (  # noqa: F401
    SIXTH_HARMONIC_HALF,
    adapt_inverter_error,
    standstill_compensation,
)
from imdrive.kernels.jit import njit
from imdrive.kernels.model import (
    MODEL_TABLE_POINTS,
    model_inductances,
    reference_magnetising,
    table_interp,
    update_magnetising,
)
from imdrive.kernels.r1_standstill import R1_STANDSTILL_PARAMS, R1_STANDSTILL_STATE
from imdrive.kernels.records import b1, c16, f8, i8, record_dtype
from imdrive.kernels.speed_control import speed_pi_gains

#: Parameters of the speed and current controllers (gains from :mod:`imdrive.design.gains`).
CONTROL_PARAMS = record_dtype(
    [
        ("n_p", f8),  # pole pairs (the controller knows them)
        ("kp_w", f8),  # speed PI proportional gain, A/(rad/s)
        ("ki_w", f8),  # speed PI integral gain, A/rad
        ("kp_i", f8),  # current PI proportional gain, V/A
        ("ki_i", f8),  # current PI integral gain, V/(A s)
        ("i_max", f8),  # stator current magnitude limit, A
        ("v_max", f8),  # voltage magnitude limit (the inverter's linear range), V
        ("decouple", b1),  # cross-coupling and back-emf feed-forward on
        ("dec_meas", b1),  # cross-coupling decoupled on the measured current (else the reference)
        ("R_a", f8),  # active resistance, V/A (0: none; kernels/current_control.py)
        ("angle_advance", f8),  # where in the next periods the voltage acts, periods (0.5, 1.5)
        ("dtc_u", f8),  # dead-time compensation: assumed t_d f_sw Vdc_meas per phase, V (0: off)
        ("dtc_band", f8),  # its current band (smooth sign), A
        # switching bridge: Vdc_meas Ts / sigma_L1_hat, the scale of the current's ripple at the
        # commutations, whose shape the compensation follows (0: the band's sign model)
        ("dtc_ripple", f8),
        # the inverter's voltage error per phase as a function of the phase current (odd:
        # the nodes i >= 0 from i = 0, u(0) = 0); ie_n > 0 replaces dtc_u's sign model
        ("ie_n", i8),
        ("ie_i", f8, (MODEL_TABLE_POINTS,)),  # phase current at the nodes, A
        ("ie_u", f8, (MODEL_TABLE_POINTS,)),  # the voltage the inverter loses there, V
        # online scaling of the inverter-error compensation from the sixth harmonic
        ("ie_rate", f8),  # its rate, 1/s (0: off; the scale stays 1)
        ("ie_wc", f8),  # the current loop's bandwidth, rad/s (phase and gain at 6 w_e)
        ("ie_wmin", f8),  # lowest |w_e| it adapts at, rad/s
        ("ie_r1", b1),  # R1_hat was identified at standstill: move the scale's share out of it
        # the scale reads the stator voltage equation's residual (0: the current PIs' output)
        ("ie_veq", b1),
        ("fw", b1),  # field weakening by voltage feedback
        ("fw_v", f8),  # voltage use it holds, fraction of v_max
        ("fw_rate", f8),  # its integral gain, 1/s per unit of voltage use
        ("fw_min", f8),  # lowest flux factor
        ("fw_bound", b1),  # the flux factor is bounded by the no-load voltage at fw_v
        ("w_fw_sched", b1),  # speed PI gains times k, k^2 in field weakening (speed_control.py)
        ("r1_settle", f8),  # online R1 law held this long after the speed reference moved, s
        ("or_wmin", f8),  # orientation check from this |w_e|, rad/s (0: off)
        ("dfo_wmin", f8),  # the frame follows the estimator's flux from this |w_e|, rad/s
        ("or_trip", f8),  # misoriented and voltage-limited this long: realign, s
    ]
    + R1_STANDSTILL_PARAMS  # the standstill R1 test (kernels/r1_standstill.py)
)

#: State of the controller (and of the open-loop voltage drive).
CONTROL_STATE = record_dtype(
    [
        ("theta_e", f8),  # field angle of the controller's synchronous frame, rad
        ("w_e", f8),  # synchronous speed used by the controller, rad/s
        ("int_w", f8),  # speed PI integral state, A
        ("int_dq", c16),  # current PI integral states (d + j q), V
        ("i_ref_dq", c16),  # current reference id* + j iq*, A
        ("i_s_dq", c16),  # measured current in the controller's frame, A
        ("psi_hat", f8),  # the controller's rotor-flux model, Wb
        ("theta_ol", f8),  # angle of the open-loop voltage, rad
        ("fw_cut", f8),  # field weakening: 1 - the flux factor (0: rated flux)
        ("ie_dk", f8),  # the inverter-error compensation's scale less 1 (online, ie_rate)
        ("ie_vm", f8),  # running mean of the current PI's output across the current, V
        ("ie_c0", f8),  # the compensation's apparent resistance at standstill, per unit scale, ohm
        ("ie_rm", c16),  # running mean of the stator equation's residual in the frame, V
        ("ie_rp", f8),  # the last period's residual across the current, high-passed, V
        ("ie_thi", f8),  # and the angle of that period's current, rad
        ("w_sl", f8),  # the slip command of the last period, electrical rad/s
        ("w_ref_prev", f8),  # the speed reference at the last sample, mechanical rad/s
        ("ref_moved_at", f8),  # when the speed reference last moved, s (-inf: never)
        ("or_time", f8),  # how long the orientation check has seen the frame off, s
    ]
    + R1_STANDSTILL_STATE
)

#: Log fields of this block.
LOG_FIELDS = (
    "speed_ref",
    "id_ref",
    "iq_ref",
    "i_d",
    "i_q",
    "theta_e",
    "R1_id_status",  # the standstill R1 test (kernels/r1_standstill.py): 0 not run, 1, 2, 3
)


@njit(cache=True)
def wrap_angle(th):
    """Wrap an angle to [-pi, pi)."""
    return (th + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True)
def open_loop_voltage(s, v_amp, f_Hz, Ts):
    """Balanced sinusoidal voltage for the next period (updates the angle in ``c``), sampled at
    the middle of the period: the held voltage has the continuous sinusoid's phase (its
    amplitude is reduced by sinc(w Ts/2), 6e-5 at 60 Hz, 10 kHz)."""
    w = 2.0 * math.pi * f_Hz
    th = s.theta_ol + 0.5 * w * Ts
    s.theta_ol = wrap_angle(s.theta_ol + w * Ts)
    return v_amp * math.cos(th), v_amp * math.sin(th)


@njit(cache=True)
def foc_step(p, m, s, i_alpha, i_beta, w_fb_m, w_ref_m, psi_ref, i_inj, Ts, psi_obs_ab, psi_mag):
    """One period of field-oriented speed control, indirect or, on an estimator's flux,
    direct (updates ``s``).

    Parameters
    ----------
    p : CONTROL_PARAMS record
    m : MODEL_STATE record
        The controller's machine model; ``R2_hat`` is the estimate the slip uses.
    s : CONTROL_STATE record
        Updated in place.
    i_alpha, i_beta : float
        Measured stator current, stationary frame, A.
    w_fb_m : float
        Speed feedback, mechanical rad/s (measured or estimated).
    w_ref_m : float
        Speed reference, mechanical rad/s.
    psi_ref : float
        Rotor-flux reference, Wb.
    i_inj : float
        Component added to the flux-current reference id* (the injected sinusoid), A.
    Ts : float
        Control period, s.
    psi_obs_ab, psi_mag : complex, float
        The speed estimator's rotor-flux estimate, stationary frame, Wb (``0j``: none, the
        frame integrates the slip; module docstring), and a flux magnitude an R̂2 error does
        not move, for the magnetising curve (Wb; 0: the flux model's; an encoder drive's).

    Returns
    -------
    v_alpha, v_beta : float
        Voltage reference for the next period, stationary frame, V.
    """
    M, L1, L2, sigma_L1 = model_inductances(m)
    n_p = p.n_p
    i_max = p.i_max

    # flux-current reference, plus the injected component (persistent excitation); with a
    # magnetising curve, at the secant inductance the reference flux needs (M without one)
    M_ref = reference_magnetising(m, psi_ref, s.i_ref_dq.imag)
    id_ref = min(psi_ref / M_ref + i_inj, i_max)

    # the controller's rotor-flux model (exact for id* held over the period)
    T2_hat = L2 / m.R2_hat
    g = math.exp(-Ts / T2_hat)
    psi_hat = s.psi_hat
    # floor: keeps slip and torque current finite while the machine is still unmagnetised
    psi_div = max(psi_hat, 0.05 * M * abs(id_ref), 1e-6)
    # speed PI -> torque command, expressed as the q current at the reference flux; divided by
    # the modelled flux so the torque does not follow flux changes (injection, magnetising)
    iq_max = math.sqrt(max(i_max * i_max - id_ref * id_ref, 0.0))
    err_w = w_ref_m - w_fb_m
    kp_w, ki_w = speed_pi_gains(p, s)  # in field weakening scaled by the flux factor
    u_unsat = kp_w * err_w + s.int_w
    flux_gain = psi_ref / psi_div
    iq_ref = min(max(u_unsat * flux_gain, -iq_max), iq_max)
    s.int_w += ki_w * Ts * err_w + (iq_ref / flux_gain - u_unsat)

    # synchronous frame: slip from the estimated rotor time constant
    th = s.theta_e
    if psi_obs_ab != 0j and abs(s.w_e) >= p.dfo_wmin and abs(psi_obs_ab) > 0.5 * psi_ref:
        # direct field orientation on the estimator's own flux (module docstring)
        th = math.atan2(psi_obs_ab.imag, psi_obs_ab.real)
    cs = math.cos(th)
    sn = math.sin(th)
    i_d = cs * i_alpha + sn * i_beta
    i_q = -sn * i_alpha + cs * i_beta
    w_sl = M * iq_ref / (T2_hat * psi_div)
    s.w_sl = w_sl
    s.psi_hat = g * psi_hat + (1.0 - g) * M * id_ref
    w_e = n_p * w_fb_m + w_sl

    # current PIs with decoupling (control.current_controller, kernels/current_control.py);
    # the d axis has priority in the voltage limit (keeps flux)
    kp = p.kp_i
    ki = p.ki_i
    e_d = id_ref - i_d
    e_q = iq_ref - i_q
    ff_d, ff_q = decoupling_voltage(p, w_e, sigma_L1, M / L2 * psi_hat, id_ref, iq_ref, i_d, i_q)
    v_d_unsat = kp * e_d + s.int_dq.real + ff_d
    v_q_unsat = kp * e_q + s.int_dq.imag + ff_q
    v_max = p.v_max
    v_d = min(max(v_d_unsat, -v_max), v_max)
    v_q_max = math.sqrt(max(v_max * v_max - v_d * v_d, 0.0))
    v_q = min(max(v_q_unsat, -v_q_max), v_q_max)
    s.int_dq = complex(
        s.int_dq.real + (ki * Ts * e_d + (v_d - v_d_unsat)),
        s.int_dq.imag + (ki * Ts * e_q + (v_q - v_q_unsat)),
    )
    dth = 0.0
    if p.ie_rate > 0.0 and v_q_unsat == v_q and v_d_unsat == v_d:
        u_d = v_d - ff_d - p.R_a * i_d
        u_q = v_q - ff_q - p.R_a * i_q
        adapt_inverter_error(p, s, m, u_d, u_q, i_d, i_q, th, w_e, Ts)
    elif p.or_wmin > 0.0 and (v_q_unsat != v_q or v_d_unsat != v_d):
        dth = check_orientation(p, s, m, v_d, v_q, i_d, i_q, w_e, sigma_L1, Ts)
    elif s.or_time > 0.0:
        s.or_time = 0.0

    # back to the stationary frame at the middle of the period where the held voltage acts:
    # half a period ahead, or 1.5 periods with a one-period computation delay
    th_mid = th + p.angle_advance * w_e * Ts
    cm = math.cos(th_mid)
    sm = math.sin(th_mid)
    v_alpha = cm * v_d - sm * v_q
    v_beta = sm * v_d + cm * v_q
    v_alpha, v_beta = limit_magnitude(v_alpha, v_beta, v_max)

    s.theta_e = wrap_angle(th + dth + w_e * Ts)
    s.w_e = w_e
    s.i_ref_dq = complex(id_ref, iq_ref)
    s.i_s_dq = complex(i_d, i_q)
    update_magnetising(m, psi_mag if psi_mag > 0.0 else s.psi_hat, s.i_ref_dq)  # M_hat(psi_m)
    return v_alpha, v_beta


@njit(cache=True)
def check_orientation(p, s, m, v_d, v_q, i_d, i_q, w_e, sigma_L1, Ts):
    """Realign the controller's frame on the rotor flux when the voltage limit has cost the
    current control its orientation (updates ``s``; returns the turn of the frame from the
    next period on, rad; 0: none).

    Indirect field orientation integrates the stator frequency and has no feedback on the
    angle: if the current control is lost in the voltage limit (a ramp into deep field
    weakening with the current at its limit), the frame can slip from the flux and stay
    there. At twice the rated speed the frame was found 90 degrees off, the d-axis voltage at
    the limit against the back-emf of a flux on the controller's q axis, a stable state.
    Above ``p.or_wmin`` the back-emf dominates the stator voltage, so its steady-state
    estimate ``e = v - R1 i - j w_e sigma_L1 i`` (controller's frame) shows where the flux is:
    ``e = j w_e (M/L2) psi exp(j delta)``. Called only while the voltage is limited; when
    ``|delta| > pi/3`` for ``p.or_trip`` the frame turns by ``delta`` and the current PIs'
    integral states turn with it (the same stationary-frame voltage). A correctly oriented
    drive never comes near the threshold.
    """
    if abs(w_e) < p.or_wmin:
        s.or_time = 0.0
        return 0.0
    e_d = v_d - m.R1_hat * i_d + w_e * sigma_L1 * i_q
    e_q = v_q - m.R1_hat * i_q - w_e * sigma_L1 * i_d
    sg = 1.0 if w_e > 0.0 else -1.0
    delta = math.atan2(-sg * e_d, sg * e_q)
    if abs(delta) <= math.pi / 3.0:
        s.or_time = 0.0
        return 0.0
    s.or_time += Ts
    if s.or_time < p.or_trip:
        return 0.0
    s.or_time = 0.0
    s.int_dq = s.int_dq * complex(math.cos(delta), -math.sin(delta))
    return delta


@njit(cache=True)
def log_control(row, s, w_ref_m, theta_k):
    """Write this block's :data:`LOG_FIELDS` into the log record ``row``.

    ``w_ref_m`` is the speed reference (mechanical rad/s) and ``theta_k`` the field angle at
    this sample (before :func:`foc_step` advanced it).
    """
    row.speed_ref = w_ref_m
    row.id_ref = s.i_ref_dq.real
    row.iq_ref = s.i_ref_dq.imag
    row.i_d = s.i_s_dq.real
    row.i_q = s.i_s_dq.imag
    row.theta_e = theta_k
    row.R1_id_status = s.dc_status


@njit(cache=True)
def inverter_error(p, i_x):
    """The inverter's voltage error of one phase at phase current ``i_x`` (A) from the
    identified table, V: odd in ``i_x``, linear between the nodes, held past the last."""
    u, _ = table_interp(abs(i_x), p.ie_i, p.ie_u, p.ie_n)
    return u if i_x >= 0.0 else -u


@njit(cache=True)
def r1_masked_by_inverter_error(p, s, m, i_ab):
    """Whether the stator resistance's drop is below twice the inverter's voltage error the
    controller compensates, ``R1 |i| < 2 (4/3) k u_c`` (the compensation's six-step vector,
    ``(4/3) k u_c`` long on the average, :func:`adapt_inverter_error`): there an online R1
    law reads what is left of that error (its shape at the current's zero crossings, which no
    sign model describes) as a resistance. Measured on the dead-time bridge at 0.1-0.3 of the
    rated speed: the law drove the speed 18-39 rpm off at no load and R2_hat 4 % low; the
    standstill identification alone left both within goal. ``i_ab``: the measured current
    (complex), A. False without compensation.

    ``R1`` is ``m.R1_gate`` (R1_hat(0), then the standstill test's), not the law's own R1_hat,
    which opened its own gate as it rose; and the margin is 2. At the bare threshold, on the
    realistic presets' drive (Aalto 2.2 kW, half the rated speed, no load) the law read the
    residual as R1, climbed to 1.3 R1 in 6 s and the drive lost control (2 of the 72 runs of
    :mod:`imdrive.studies.realistic_envelope`); with the margin none, 16 of 24 ``ok``."""
    if not has_feedforward(p):
        return False
    u_c = p.ie_u[p.ie_n - 1] if p.ie_n > 0 else p.dtc_u
    R1 = m.R1_gate if m.R1_gate > 0.0 else m.R1_hat
    return R1 * abs(i_ab) < 2.0 * (4.0 / 3.0) * (1.0 + s.ie_dk) * u_c


#: The switching bridge's dead-time compensation (:func:`dead_time_feedforward`): each of its two
#: signs smooth over ``RIPPLE_EDGE delta`` (``delta`` the ripple at the commutations), but never
#: over less than ``RIPPLE_EDGE`` times the sign model's band, and whole from ``delta`` on.
RIPPLE_EDGE = 0.25


@njit(cache=True, inline="always")
def _bridge_loss_sign(i_x, delta, band):
    """The switching bridge's dead-time loss of one phase per unit of the whole loss, as the
    compensation models it: ``(sgn_b(i_x + c) + sgn_b(i_x - c))/2``, each sign smooth over
    ``b = max(RIPPLE_EDGE delta, RIPPLE_EDGE band)`` (at most ``band``) and centred at
    ``c = max(delta - b, 0)``, so it is whole from ``delta`` on (or from ``b``, with no ripple).

    The floor on ``b``: the measured current's noise and offsets (20 mA each on the realistic
    drive) would toggle a sharper edge on a phase that sits near zero, as one does at
    standstill, a few volts of noise against the ``R1 |i|`` the drive holds there (the
    sensorless drive's frame then drifted 120 degrees while magnetising)."""
    b = min(max(RIPPLE_EDGE * delta, RIPPLE_EDGE * band), band)
    c = max(delta - b, 0.0)
    return 0.5 * (smooth_sign(i_x + c, b) + smooth_sign(i_x - c, b))


@njit(cache=True)
def _table_loss(p, i_x):
    """The identified table's loss magnitude at ``|i_x|``, from its first node above zero on
    (below it the table holds the DC test's own smoothing, which the ripple shape replaces)."""
    u, _ = table_interp(max(abs(i_x), p.ie_i[min(1, p.ie_n - 1)]), p.ie_i, p.ie_u, p.ie_n)
    return u


@njit(cache=True)
def dead_time_feedforward(p, i_alpha, i_beta, v_alpha=0.0, v_beta=0.0):
    """Dead-time compensation added to the voltage reference, ``(alpha, beta)``, V.

    Each phase's pole voltage is raised by ``sgn_b(i_x) u`` with ``u = t_d,assumed f_sw
    Vdc_meas`` (``p.dtc_u``), the averaged loss the dead time causes, signed by the measured
    phase current (smooth inside ``p.dtc_band``). With an identified inverter-error table
    (``p.ie_n > 0``, a commissioning's standstill DC test) each phase is raised by the
    table's ``u(i_x)`` instead (:func:`inverter_error`).

    On the switching bridge (``p.dtc_ripple > 0``) the loss has the shape of the current's
    ripple at the leg's commutations, ``delta_x`` (:func:`commutation_ripple`, from the
    reference ``(v_alpha, v_beta)`` before the compensation): none while ``|i_x| < delta_x``,
    whole beyond. The compensation follows it, ``u (sgn_b(i_x + c_x) + sgn_b(i_x - c_x))/2``
    (:func:`_bridge_loss_sign`), whole from ``delta_x`` on and a little early rather than
    late: where it falls short of a whole loss, just past ``delta_x``, the
    residual holds the current back instead of pushing it through zero. A fixed band wider
    than the ripple does that: the current stalls at each zero crossing until the PIs have
    built the missing voltage, and its fundamental lags by an angle that falls as ``1/|i|``.
    The R2 injection's ``delta i_d`` modulates ``|i|`` and with it the lag: a voltage error
    across the current in phase with the injection, which the MRAS's voltage model turns into
    an in-phase d-axis flux error, the signal the compensator reads as an R2 error (measured on
    Table IV at 0.1 of the rated speed with the 0.2 A band: 0.038 V per ampere injected,
    R2_hat -3.4 % at no load and -6.6 % regenerating at the rated torque; with this shape
    +1.6 and -0.1 %). Close to the loss's shape inside ``|i_x| < delta_x`` too, it also leaves
    little six-step residual, so the online scale (:func:`adapt_inverter_error`) learns the
    true ratio (1.24 for 2 us assumed as 1.6 us, against 1.18 with the 0.2 A band at 0.3 of
    the rated speed).

    With both, an identified table on the switching bridge, the table gives each phase's loss
    magnitude (:func:`_table_loss`) and the ripple its shape. Until 2026-11-29 the table
    replaced the ripple shape, so a commissioned drive compensated with the table's fixed
    band (the ideal table's first node, 0.2 A on Table IV): a voltage error across the
    current of 0.3-0.5 V at no load on the realistic drive at 45-100 rpm, which the adaptive
    observer read as a speed error (lost control at 12 of 15 points of docs/estimators.md's
    low-speed table, the EKF 3.8-8 rpm off at light load). With the shape: AFO, EKF and MRAS
    within 0.4 rpm at every motoring point and at no load there.
    """
    ia, ib, ic = phase_values(i_alpha, i_beta)
    if p.ie_n > 0 and p.dtc_ripple > 0.0:
        ra, rb, rc = commutation_ripple(v_alpha, v_beta, math.sqrt(3.0) * p.v_max, p.dtc_ripple)
        return clarke(
            _bridge_loss_sign(ia, ra, p.dtc_band) * _table_loss(p, ia),
            _bridge_loss_sign(ib, rb, p.dtc_band) * _table_loss(p, ib),
            _bridge_loss_sign(ic, rc, p.dtc_band) * _table_loss(p, ic),
        )
    if p.ie_n > 0:
        return clarke(inverter_error(p, ia), inverter_error(p, ib), inverter_error(p, ic))
    u = p.dtc_u
    if p.dtc_ripple > 0.0:
        ra, rb, rc = commutation_ripple(v_alpha, v_beta, math.sqrt(3.0) * p.v_max, p.dtc_ripple)
        return clarke(
            _bridge_loss_sign(ia, ra, p.dtc_band) * u,
            _bridge_loss_sign(ib, rb, p.dtc_band) * u,
            _bridge_loss_sign(ic, rc, p.dtc_band) * u,
        )
    return clarke(
        smooth_sign(ia, p.dtc_band) * u,
        smooth_sign(ib, p.dtc_band) * u,
        smooth_sign(ic, p.dtc_band) * u,
    )


@njit(cache=True)
def commutation_ripple(v_alpha, v_beta, Vdc_meas, ripple_scale):
    """Each phase current's deviation from its sample at its leg's commutations, A.

    On the switching bridge (a symmetric carrier that starts and ends the period on the zero
    vector 000, min-max injection, :func:`imdrive.kernels.inverter.gate_commands`) leg ``x``
    is high over ``[(1 - d_x) Ts/2, (1 + d_x) Ts/2]``. With the back-emf constant over the
    period, the phase current moves at ``(v_xn - mean v_xn)/sigma_L1`` about its sample at
    the period's start (``v_xn`` the phase voltage, the neutral's share removed), so at the
    leg's turn-on it is off the sample by

        delta_x = (Vdc Ts / sigma_L1) | sum_y max(0, d_y - d_x)/6 + (d_x - d_mean)(1 - d_x)/2 |

    and by ``-delta_x`` at its turn-off (the waveform is symmetric about mid-period). The
    dead time costs ``u/2`` at each commutation, signed by the current there: the leg's loss
    is ``(u/2)(sgn(i_x + delta_x) + sgn(i_x - delta_x))``, none while the ripple straddles
    zero. (This project's derivation from the switching sequence; the dead-time loss itself:
    Jeong & Park, IEEE Trans. Ind. Electron. 38(2), 1991.) ``ripple_scale``:
    ``Vdc Ts / sigma_L1_hat``, A; ``(v_alpha, v_beta)``: the reference the duties come from,
    V. Returns ``(delta_a, delta_b, delta_c)``.
    """
    da, db, dc = duty_cycles(v_alpha, v_beta, Vdc_meas)
    d_mean = (da + db + dc) / 3.0
    return (
        _leg_ripple(da, db, dc, d_mean, ripple_scale),
        _leg_ripple(db, dc, da, d_mean, ripple_scale),
        _leg_ripple(dc, da, db, d_mean, ripple_scale),
    )


@njit(cache=True, inline="always")
def _leg_ripple(dx, dy, dz, d_mean, ripple_scale):
    """:func:`commutation_ripple` of the leg of duty ``dx`` (the others ``dy``, ``dz``), A."""
    over = max(dy - dx, 0.0) + max(dz - dx, 0.0)
    return ripple_scale * abs(over / 6.0 + (dx - d_mean) * (1.0 - dx) * 0.5)


@njit(cache=True)
def dead_time_advance(p, s, Ts):
    """How far the switching bridge's modulator moves every gate command earlier, s: half the
    dead time the compensation assumes, ``(1 + s.ie_dk) t_d,assumed / 2`` (0 without the
    bridge's compensation, ``p.dtc_ripple = 0``, or with the identified table).

    The dead time delays a leg's turn-on while its current is positive and its turn-off while
    it is negative: the loss :func:`dead_time_feedforward` restores, and a delay of the
    pulse's centre by ``t_d/2`` either way (``t_d`` while the ripple straddles zero, none
    when it turns the other way; ``t_d/2`` on the average), which widening the pulse
    symmetrically leaves. The current is sampled in the middle of the zero vector of
    symmetric PWM, where its ripple is nil; the centres' delay moves the pattern, and the
    sample lands ``t_d/2`` before the zero vector's middle, off the current's mean by
    ``v t_d / (2 sigma_L1)``, a right angle ahead of the current at no load. The MRAS's current
    model turns by that over ``|i|``, and the estimate is off by that angle over ``T2``:
    a bias proportional to the speed (Table IV at the rated speed and no load on the 2 us
    bridge, compensated exactly: the sample 0.045 A off, 6.5 mrad, 0.35 rpm by this
    estimate; the estimate measured 0.47 rpm low from it). Moving the commands earlier by
    ``t_d/2`` puts the pulses back (this project's analysis; the dead time's edges: Jeong &
    Park, IEEE Trans. Ind. Electron. 38(2), 1991).
    """
    if p.dtc_ripple <= 0.0 or p.dtc_u <= 0.0:
        return 0.0
    return 0.5 * (1.0 + s.ie_dk) * p.dtc_u * Ts / (math.sqrt(3.0) * p.v_max)


@njit(cache=True)
def inverter_feedforward(p, s, i_alpha, i_beta, Ts, v_alpha=0.0, v_beta=0.0):
    """The inverter-error compensation added to the voltage reference, ``(alpha, beta)``, V.

    With the identified table (``p.ie_n > 0``) each phase's error is taken at the current of
    the middle of the period where the voltage acts: the measured current turned by the
    controller's frequency over ``p.angle_advance`` periods (0.5, or 1.5 with a one-period
    delay), so the compensation changes sign with the current, not one period after it. The
    switching bridge's sign model (``p.dtc_ripple > 0``, shaped by the ripple the reference
    ``(v_alpha, v_beta)`` causes, V) takes the same turned current: taken at the sample, the
    compensation lagged the loss by ``angle_advance`` periods, a voltage error
    ``j w_e angle_advance Ts`` times the loss's fundamental, across the current, which the
    MRAS's voltage model read along with the compensation it subtracts (Table IV at the
    rated speed and no load, 2 us compensated exactly, no injection: the estimate +0.28 rpm
    off once the pulses' centres were right, :func:`dead_time_advance`; -0.02 rpm with the
    turned current; with the R2 compensator R2_hat +0.62 % against +0.01 %). Otherwise
    :func:`dead_time_feedforward` on the measured current (the average inverter model's
    sign model, whose loss acts at the sample's current).
    """
    if p.ie_n > 0 or p.dtc_ripple > 0.0:
        th = s.w_e * p.angle_advance * Ts
        c = math.cos(th)
        sn = math.sin(th)
        i_a, i_b = c * i_alpha - sn * i_beta, sn * i_alpha + c * i_beta
        dv_a, dv_b = dead_time_feedforward(p, i_a, i_b, v_alpha, v_beta)
    else:
        dv_a, dv_b = dead_time_feedforward(p, i_alpha, i_beta, v_alpha, v_beta)
    if s.ie_dk != 0.0:  # the online scale (:func:`adapt_inverter_error`)
        k = 1.0 + s.ie_dk
        return k * dv_a, k * dv_b
    return dv_a, dv_b


@njit(cache=True)
def field_weakening(p, s, v_use, Ts, k_max=1.0):
    """The field-weakening flux factor for this period (``p.fw``; updates ``s.fw_cut``).

    Voltage feedback: the factor ``k = 1 - s.fw_cut`` integrates the headroom,

        dk/dt = fw_rate (fw_v - v_use),    fw_min <= k <= 1,

    so below base speed (voltage use under ``fw_v``) it stays at 1 and above it the flux
    reference ``k psi*`` falls roughly as ``1/w`` to hold the voltage at ``fw_v`` of the
    inverter's limit. No base speed or machine data enter: the voltage the current
    controllers need decides. ``v_use``: magnitude of the last commanded voltage over
    ``Vdc_meas/sqrt 3``. ``k_max`` (``control.field_weakening_bound``; kernels/stages.py
    computes it from the controller's model): the flux factor whose no-load voltage
    ``w_e (L1/M) k psi*`` is ``fw_v`` of the limit. Regenerating, the voltage needed falls
    below the no-load one and the feedback alone raised ``k`` back towards 1; the rotor flux
    followed a rotor time constant later and overshot the limit. The bound is the
    conventional ``1/w`` flux programme, here an upper limit of the voltage feedback (the
    two are compared in Kim and Sul, IEEE Trans. Ind. Electron. 44(4), 1997). Returns ``k``.
    """
    k = 1.0 - s.fw_cut + Ts * p.fw_rate * (p.fw_v - v_use)
    k = min(max(k, p.fw_min), 1.0, max(k_max, p.fw_min))
    s.fw_cut = 1.0 - k
    return k
