"""Online scale of the inverter-error compensation (the controller's, :mod:`imdrive.kernels.ifoc`).

The part of the inverter's voltage error that the feed-forward does not cancel,
``(u - k u_c) sgn(i_x)`` per phase, is a six-step vector of magnitude ``4/3 (u - k u_c)``
pointing at the 60-degree sector of the current (Jeong & Park, "The analysis and compensation
of dead-time effects in PWM inverters", IEEE Trans. Ind. Electron. 38(2), 1991). Across the
current vector (angle ``theta_i``) it is ``-4/3 (u - k u_c) sin(saw(theta_i))`` (``saw``: the
angle from the nearest sector centre), whose first harmonic is ``-c6 (u - k u_c) sin(6
theta_i)`` with ``c6 = (8/pi)(1/10 + 1/14) = 0.4365``. No other part of an ideal sinusoidal
machine's voltage has a sixth harmonic locked to the current, so its correlation with
``sin(6 theta_i)`` measures ``u - k u_c`` and :func:`adapt_inverter_error` scales the
compensation ``k`` until it vanishes.

Where that residual is read matters on a sensorless drive. The current PIs' output
``u_dq`` (the first form of the law, ``control.inverter_error_signal = "current-loop"``) holds
it through the closed current loop ``a_c/(s + a_c)``, but not only that way: the residual
also enters the speed estimator's voltage model, the speed estimate carries its sixth
harmonic, and the speed PI's proportional gain passes it into ``iq*`` (and the slip); the
current PIs' output following that reference ripple is a second sixth harmonic across the
current, largest at light load, where ``iq*`` is across the current. Measured on Table IV
with the MRAS (dead-time bridge, 2 us compensated as 1.6 us, no load): the law's loop gain,
``d(correlation)/dk`` against its design ``c6/2 |H| u_c``, is +0.14 at 0.6 x the rated speed,
+0.10 at 1 x and **-0.42 at 1.5 x** (+1.0 at full load, +1.25-1.5 with the speed measured).
At 1.5 x the equilibrium ``k = u/u_c`` is unstable: the scale ran to its bound (-0.75 from
where the speed ramp left it) and with it R1_hat, by the standstill R1 identification's share
(:func:`adapt_inverter_error`, ``p.ie_r1``), to 3.3 R1; the speed ended +1.39 rpm off.

The default reads the residual where the controller's own voltage cannot reach it, in the
stator voltage equation over the last period (:func:`stator_residual`): the voltage the
controller applied less its compensation, less ``sigma_L1 di/dt + R1_hat i``, is the residual
plus the back-emf, whatever made the current move (the PI's reaction, the speed loop's ripple,
the feed-forward). The back-emf is a constant in the controller's frame and a first-order
high-pass there removes it, before the projection across the current (a wobble of the
current's angle would otherwise turn the back-emf's along-current part into a sixth harmonic
of its own); ``R1_hat i`` lies along the current, so the resistance estimate does not enter
the projection. The loop gain is then 1 at every speed and load and with either speed
feedback (``control.inverter_error_signal = "stator-voltage"``).
"""

from __future__ import annotations

import math

from imdrive.kernels.jit import njit
from imdrive.kernels.model import model_inductances

#: Half the sixth-harmonic coefficient ``c6/2`` of a six-step error across the current
#: (:func:`adapt_inverter_error`): ``(4/pi)(1/10 + 1/14)``.
SIXTH_HARMONIC_HALF = 4.0 / math.pi * (1.0 / 10.0 + 1.0 / 14.0)

#: The running mean's corner, per unit of the sixth harmonic's frequency: its high-pass leads
#: by ``atan(0.2)`` and passes ``cos(atan(0.2))`` there.
MEAN_CORNER = 0.2
HIGH_PASS_GAIN = 1.0 / math.sqrt(1.0 + MEAN_CORNER * MEAN_CORNER)


@njit(cache=True)
def stator_residual(p, s, m, v_ab, i_prev_ab, i_ab, Ts):
    """The inverter's voltage error left over the last period, across its current (updates
    ``s.ie_rm``, ``s.ie_rp``, ``s.ie_thi``; module docstring).

    ``r = v - sigma_L1_hat (i - i_prev)/Ts - R1_hat i_m`` (stationary frame; ``v``: the voltage
    the controller applied over the period less its compensation, as the estimators get it;
    ``i_m`` the mean of the period's two current samples) is the residual ``(u - k u_c)
    sgn(i_x)`` plus the back-emf. Turned into the controller's frame at the period's middle
    (``s.theta_e - w_e Ts/2``, before :func:`imdrive.kernels.ifoc.foc_step` advances it), its
    running mean (first order at ``MEAN_CORNER 6 |w_e|``) is taken off, and what is left is
    projected across ``i_m``: ``s.ie_rp``, V, at the current's angle ``s.ie_thi``.
    ``v_ab``, ``i_prev_ab``, ``i_ab``: complex, V and A; ``Ts``: s.
    """
    _, _, _, sigma_L1 = model_inductances(m)
    i_m = 0.5 * (i_ab + i_prev_ab)
    di = i_ab - i_prev_ab
    r_alpha = v_ab.real - sigma_L1 * di.real / Ts - m.R1_hat * i_m.real
    r_beta = v_ab.imag - sigma_L1 * di.imag / Ts - m.R1_hat * i_m.imag
    th_m = s.theta_e - 0.5 * s.w_e * Ts
    c = math.cos(th_m)
    sn = math.sin(th_m)
    r_d = c * r_alpha + sn * r_beta
    r_q = -sn * r_alpha + c * r_beta
    w6 = 6.0 * max(abs(s.w_e), p.ie_wmin)
    if s.ie_rm == 0.0:
        s.ie_rm = complex(r_d, r_q)
    a = min(MEAN_CORNER * w6 * Ts, 1.0)
    m_d = s.ie_rm.real + (r_d - s.ie_rm.real) * a
    m_q = s.ie_rm.imag + (r_q - s.ie_rm.imag) * a
    s.ie_rm = complex(m_d, m_q)
    h_d = r_d - m_d
    h_q = r_q - m_q
    i_d = c * i_m.real + sn * i_m.imag
    i_q = -sn * i_m.real + c * i_m.imag
    i_mag = math.hypot(i_d, i_q)
    if i_mag < 1e-6:
        s.ie_rp = 0.0
        return
    s.ie_rp = (i_d * h_q - i_q * h_d) / i_mag
    s.ie_thi = th_m + math.atan2(i_q, i_d)


@njit(cache=True)
def adapt_inverter_error(p, s, m, u_d, u_q, i_d, i_q, th, w_e, Ts):
    """Scale the inverter-error compensation so the sixth harmonic it leaves vanishes.

    With ``p.ie_veq`` (the default) the residual across the current is the stator voltage
    equation's, ``s.ie_rp`` at the angle ``s.ie_thi`` (:func:`stator_residual`, this period),
    high-passed (lead ``atan(0.2)``, gain ``cos(atan(0.2))``); otherwise the current PIs'
    output ``u_dq`` (the voltage reference less the feed-forward terms), which holds the
    residual through their closed loop ``a_c/(s + a_c)`` with gain ``|H|`` and lag ``phi`` at
    ``6 w_e``, and whatever else drives the current (module docstring: on a sensorless drive
    the speed estimate's sixth harmonic, through the speed loop). So the mean of

        p = u_perp,hp sin(6 theta_i - phi)  =  -c6/2 |H| (u - k u_c),

    and ``dk/dt = -rate 2/c6 p / (u_c |H|) = rate (u/u_c - k)`` drives the scale ``k`` to the
    ratio of the true error to the assumed one (this project's adaptation law; the same signal
    is what a repetitive dead-time compensator cancels). The current-loop form's mean of
    ``u_perp`` is a first-order low-pass at ``6 |w_e| / 5`` (its high-pass leads by
    ``atan(1/5)``, included in ``phi``). Only above ``p.ie_wmin`` (the sixth harmonic then lies
    well above the R2 injection's frequencies) and outside the voltage limit (checked by the
    caller). ``s.ie_dk`` holds ``k - 1`` (bounded to -0.75 ... +1).

    A standstill R1 identification (``p.ie_r1``) measured ``R1`` plus the residual's
    apparent resistance ``(u - k u_c) (sgn . i)/|i|^2`` at the magnetising current; as ``k``
    learns the residual, its share ``dk c0`` (``c0 = Re(dv conj i)/(k |i|^2)`` at standstill,
    :func:`standstill_compensation`) leaves ``m.R1_hat``, so the reference model does not
    keep a resistance error the residual no longer offsets. Only once it has identified
    (``m.R1_id``): where it could not (a magnetisation too short for the machine's T2, Krause's
    50 hp machine on the 0.5 s of ``injection-robust``), R1_hat holds no such share, and
    taking it out drove R1_hat to its floor, 0.06 R1 (with the current-loop signal, whose
    scale ran to its bound, up to 5.4 R1).
    """
    u_c = p.ie_u[p.ie_n - 1] if p.ie_n > 0 else p.dtc_u
    if u_c <= 0.0:  # nothing to scale (before the hypot: the average model runs this path)
        return
    if p.ie_veq:
        if abs(w_e) < p.ie_wmin:
            return
        gain = HIGH_PASS_GAIN
        phi = -math.atan(MEAN_CORNER)
        if w_e < 0.0:  # turning backwards, the lead in time is a lag in angle
            phi = -phi
        prod = s.ie_rp * math.sin(6.0 * s.ie_thi - phi)
    else:
        i_mag = math.hypot(i_d, i_q)
        if i_mag < 1e-6:
            return
        u_perp = (i_d * u_q - i_q * u_d) / i_mag
        # the mean runs at any speed (from its first sample), so it has settled when the
        # scale starts to adapt and no step of the PI's DC output reaches the product
        w6 = 6.0 * max(abs(w_e), p.ie_wmin)
        if s.ie_vm == 0.0:
            s.ie_vm = u_perp
        s.ie_vm += (u_perp - s.ie_vm) * min(0.2 * w6 * Ts, 1.0)
        if abs(w_e) < p.ie_wmin:
            return
        th_i = th + math.atan2(i_q, i_d)
        x = w6 / p.ie_wc
        gain = 1.0 / math.sqrt(1.0 + x * x) * 0.98058  # |H| and the high-pass's cos(atan(0.2))
        phi = math.atan(x) - math.atan(0.2)
        if w_e < 0.0:  # turning backwards, the lag in time is a lead in angle
            phi = -phi
        prod = (u_perp - s.ie_vm) * math.sin(6.0 * th_i - phi)
    dk = -p.ie_rate * prod / (SIXTH_HARMONIC_HALF * u_c * gain) * Ts
    dk_new = min(max(s.ie_dk + dk, -0.75), 1.0)
    if p.ie_r1 and m.R1_id:  # only a share the identification took in can be given back
        dR1 = (dk_new - s.ie_dk) * s.ie_c0  # the identified R1's too: the gate's (ifoc.py)
        m.R1_hat = max(m.R1_hat - dR1, 0.05 * m.R1_hat)
        m.R1_gate = max(m.R1_gate - dR1, 0.05 * m.R1_gate)
    s.ie_dk = dk_new


@njit(cache=True)
def standstill_compensation(s, dv_alpha, dv_beta, i_alpha, i_beta, w_ref):
    """Track the compensation's apparent resistance at standstill (``s.ie_c0``, ohm per unit
    of the scale): ``Re(dv conj i)/((1 + s.ie_dk) |i|^2)`` while the speed reference is zero,
    the current above 1 A and the field nearly still (the standstill R1 identification's
    own conditions, :func:`imdrive.kernels.r1_standstill.r1_standstill`)."""
    i2 = i_alpha * i_alpha + i_beta * i_beta
    if w_ref == 0.0 and i2 > 1.0 and abs(s.w_e) < math.pi:
        s.ie_c0 = (dv_alpha * i_alpha + dv_beta * i_beta) / ((1.0 + s.ie_dk) * i2)


@njit(cache=True)
def start_from_identified(s, m):
    """Start the scale from the residual the standstill test at two current levels identified
    (``m.u0_id`` along its current ``m.i_id``; :mod:`imdrive.kernels.r1_standstill`):
    the compensation along that current is ``c0 |i|`` per unit of scale
    (:func:`standstill_compensation`), so the scale that leaves no residual is ``1 + dk + u0 /
    (c0 |i|)`` (bounded as the online law's). Below the online law's lowest stator frequency
    (``p.ie_wmin``) this is the only scale the compensation gets. Clears ``m.ie_new``."""
    if m.i_id > 0.0 and s.ie_c0 != 0.0:
        dk = s.ie_dk + m.u0_id / (s.ie_c0 * m.i_id)
        s.ie_dk = min(max(dk, -0.75), 1.0)
    m.ie_new = False
