"""The R2 compensator's mechanisms for the whole speed and load range.

* the injection's voltage headroom (:func:`injection_headroom`) and the *estimation
  headroom* (:func:`headroom_weakening_input`): near and above base speed the field weakening
  lowers the flux so the injection keeps its amplitude and R2 stays observable; the cost in
  torque per ampere is :mod:`imdrive.analysis.headroom`;
* the rotor thermal model (:func:`thermal_step`, :func:`thermal_recalibrate`): rotor losses
  -> first-order thermal network -> temperature -> R2_hat, carrying R2_hat while the
  compensator holds it, recalibrated by its estimate whenever R2 is observable.

The records are the compensator's (``COMPENSATOR_PARAMS``, ``COMPENSATOR_STATE`` in
:mod:`imdrive.kernels.compensator`).
"""

from __future__ import annotations

from imdrive.kernels.jit import njit
from imdrive.kernels.model import model_inductances


@njit(cache=True)
def injection_headroom(p, s, v_use, k_flux, wrapped):
    """Voltage headroom of the injection (``p.inj_v_hi > 0``; updates ``s.inj_back``).

    Tracks the peak voltage use ``v_use`` (fraction of ``Vdc_meas/sqrt 3``) over each
    injection period; at the period's end (``wrapped``: the phase restarted this sample) the
    amplitude factor for the next period is

        a = clip((inj_v_hi - v_peak) / (inj_v_hi - inj_v_lo), 0, 1),   0 in field weakening

    held over the whole period, so the detection still sees whole periods of one sinusoid.
    The injection's own voltage ripple counts in ``v_peak``, so it backs off before the
    current controllers saturate. Returns the factor in use.
    """
    s.v_peak = max(s.v_peak, v_use)
    if wrapped:
        a = (p.inj_v_hi - s.v_peak) / (p.inj_v_hi - p.inj_v_lo)
        a = min(max(a, 0.0), 1.0)
        if k_flux < 1.0 - 1e-3 and not p.inj_fw:
            a = 0.0
        s.inj_back = 1.0 - a
        s.v_peak_last = s.v_peak
        s.v_peak = 0.0
        if p.inj_fw:
            s.inj_scale = k_flux
    if p.inj_fw:
        return (1.0 - s.inj_back) * s.inj_scale
    return 1.0 - s.inj_back


@njit(cache=True)
def headroom_weakening_input(p, s, v_use, torque_limited, k_flux):
    """The voltage use the field weakening sees with the estimation headroom (``p.inj_fw``).

    The field weakening integrates ``dk/dt = fw_rate (fw_v - v_in)`` on its flux factor ``k``
    (:func:`imdrive.kernels.ifoc.field_weakening`; ``p.fw_v``, ``p.fw_rate`` are the
    controller's values). Fed on the instantaneous voltage use its loop (crossover about
    ``fw_rate`` rad/s, 3 Hz by default) answers the injection's own voltage ripple at 2-6 Hz
    and modulates the flux with it: measured at 1600 rpm, rated load on Table IV with the
    voltage held at 0.8, the flux current swung +-0.6 A against the injection's 0.5 A and the
    speed +-10 rpm. While the injection runs (``s.v_peak_last > 0``) this returns the ``v_in``
    for which the loop integrates instead

        dk/dt = inj_fw_rate k (inj_v_peak - v_peak_last) + fw_rate min(fw_v - v_use, 0)

    * a slow term on the peak voltage use of the last whole injection period
      ``v_peak_last`` (held over the period, so it carries no ripple): it lowers the flux
      until that peak is ``inj_v_peak``, below the voltage where the injection starts to back
      off, so the injection keeps its full amplitude near and above base speed (and raises
      the flux back when there is room);
    * the field weakening's own fast term only where the voltage use exceeds ``fw_v``: the
      protection against saturation in a fast transient (a speed ramp), idle in steady state.

    Above base speed the voltage use is nearly proportional to the flux, ``v ~ k w_e psi*``,
    so ``dv/dk = v / k``: the slow term integrates ``ln k`` (the factor ``k = k_flux``, the
    field weakening's flux factor in use), and the sampled loop's gain per injection period
    is ``inj_fw_rate T_inj v`` at every speed: 0.4 at 1 /s and 2 Hz, no overshoot; hence
    the cap on ``inj_fw_rate`` per injection period where the injection is slow (large
    machines). Integrating ``k`` itself, the gain grew as ``1 / k``: at twice the rated
    speed (``k`` 0.46) it was 1.15 per period, and the flux, the torque current and the
    speed cycled at 0.3-0.4 Hz, none of the injection frequencies (Table IV, -2 x rated
    speed, full available load, R2_hat exact: 5.4 rpm peak to peak, 6.2 on the dead-time
    bridge; 0.11 and 0.40 integrating ``ln k``). The cost of the lowered flux in torque per
    ampere is
    :func:`imdrive.analysis.headroom.torque_per_ampere_at_flux`.

    ``torque_limited`` (the speed loop's torque current at its limit) hands the flux to the
    field weakening's own rule (returns ``v_use``); otherwise, while the speed gate holds the
    compensator (``s.frozen & 1``), the slow term only raises the flux. The gain
    ``inj_fw_rate`` is at most ``injection.headroom_gain_per_period`` (0.6) per injection
    period (:func:`imdrive.run.blocks.headroom_rate_per_s`).
    """
    slow = p.inj_fw_rate * k_flux * (p.inj_v_peak - s.v_peak_last)
    if torque_limited:
        # a torque beyond what the lowered flux gives: the field weakening's own rule, so the
        # estimation never costs control, whether or not the speed gate has tripped yet
        # (measured at 1.4 x base speed, rated motoring torque: the lowered flux let the load
        # run the drive away; on Krause 500 hp at rated speed, regenerating, the flux kept
        # falling with the torque current at its limit while the gate was still open)
        return v_use
    if int(s.frozen) & 1:
        # the speed is not held (a transient): the flux is only not lowered further and
        # rises back at the slow rate where the voltage leaves room: the fast rule at every
        # trip of the speed gate raised the flux at 20 /s, and at base speed with rated load
        # that step tripped the gate again, a limit cycle of +-2.5 rpm that held R2_hat 66 %
        # of the time and left it 8 % off
        slow = max(slow, 0.0)
    dk = slow + p.fw_rate * min(p.fw_v - v_use, 0.0)
    return p.fw_v - dk / p.fw_rate


#: fine decisions whose mean calibrates the thermal model's cold R2 (:func:`thermal_recalibrate`)
TH_CAL_DECISIONS = 8.0


@njit(cache=True)
def thermal_recalibrate(p, s, m):
    """The compensator's estimate recalibrates the rotor thermal model (``p.th_on``).

    Called at a decision that updated R2_hat inside the first threshold (the estimate is
    converged to within its fine band, not in its first large steps). The first
    :data:`TH_CAL_DECISIONS` such decisions calibrate the model's cold resistance as the mean
    of ``R2_hat / (1 + alpha rise)`` with the temperature rise the losses gave so far
    (R2_hat(0) may be off by tens of %, a temperature the rotor does not have): one decision
    took R2_hat where it was on entering the fine band, up to its width off, and that error
    stayed in ``R2_cold`` (Table IV, held 26 s after 1.2 R2(0): 3.8 % at the end against
    3.4 % with the approach from the other side). Every later one sets the model's
    temperature from the estimate, ``rise = (R2_hat / R2_cold - 1) / alpha``, so an error of
    the thermal parameters does not accumulate while R2 is observable.
    """
    if s.th_n < TH_CAL_DECISIONS:
        r2_cold = m.R2_hat / (1.0 + p.th_alpha * s.th_rise)
        s.th_R2_cold = (s.th_R2_cold * s.th_n + r2_cold) / (s.th_n + 1.0)
        s.th_n += 1.0
    else:
        s.th_rise = (m.R2_hat / s.th_R2_cold - 1.0) / p.th_alpha


@njit(cache=True)
def thermal_step(p, s, m, i_q, t, Ts):
    """One control period of the rotor thermal model (``p.th_on``; updates ``s.th_rise`` and,
    while the compensator holds R2_hat, ``m.R2_hat``).

    First-order thermal network of the rotor (one thermal resistance and capacitance to
    ambient), driven by the rotor copper losses the controller's model gives::

        tau dtheta/dt = Rth P_r - theta,   P_r = 1.5 R2_hat (M/L2)^2 i_q^2
        R2 = R2_cold (1 + alpha theta)      (theta above ambient)

    In rotor-flux orientation the rotor current is ``-(M/L2) i_q`` (``i_q``: the measured
    torque current in the controller's frame, A). While the compensator holds R2_hat (before
    its start, frozen by the gating, or its window refilling) R2_hat follows the model's
    relative change ``(1 + alpha theta_new) / (1 + alpha theta_old)``, from the last
    estimate; while it estimates, :func:`thermal_recalibrate` sets the model's temperature
    from the estimate. Combining a rotor-resistance estimate (where it works) with a lumped
    thermal equivalent circuit (one thermal resistance and capacitance, where it does not) is
    the scheme of C. Kral, T. G. Habetler, R. G. Harley, F. Pirker, G. Pascoli,
    H. Oberguggenberger, C.-J. M. Fenz, "Rotor temperature estimation of squirrel-cage
    induction motors by means of a combined scheme of parameter estimation and a thermal
    equivalent model", IEEE Trans. Ind. Appl. 40(4), 2004 (there for mains-fed motors at low
    load, here for the drive's unobservable intervals); the temperature rise at rated losses
    is bounded by the insulation's thermal class (IEC 60034-1: 80 K class B, 105 K class F).
    """
    M, L1, L2, sigma_L1 = model_inductances(m)
    k = M / L2
    p_r = 1.5 * m.R2_hat * k * k * i_q * i_q
    rise = s.th_rise + Ts * (p.th_Rth * p_r - s.th_rise) / p.th_tau
    if t < p.t_on or not s.live:
        r2 = m.R2_hat * (1.0 + p.th_alpha * rise) / (1.0 + p.th_alpha * s.th_rise)
        m.R2_hat = min(max(r2, p.R2_min), p.R2_max)
    s.th_rise = rise
