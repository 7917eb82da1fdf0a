"""R2 tracking around the speed estimator: the excitation before it, the law after it.

The closed loop (:func:`imdrive.kernels.stages.estimate`) and the replay of a recording
(:func:`imdrive.kernels.replay.replay_estimator`) call the same two functions each period,
so a closed-loop run's recording replayed with its own estimator and R2 law gives back its
``R2_hat`` exactly, and any law (the package's or a plug-in, through the compensator's
records) replays with any estimator:

1. :func:`excitation` -- the injected flux-current sinusoid (the compensator's phase, its
   back-off near the voltage limit), before the estimator's step, which reads it;
2. :func:`track` -- after the step: the detection's own flux error where the estimator gives
   none, the synchronous detection, the gating signals, the law's decision
   (:func:`~imdrive.kernels.compensator.compensator_step`, which writes ``R2_hat`` into the
   controller's model) and the rotor thermal model.

What :func:`track` reads of the controller is one :class:`TrackingInput`: the closed loop
builds it from its state, a replay from the recorded columns
(:data:`imdrive.kernels.recording.RECORDING`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

from imdrive.kernels.compensator import (
    compensator_gate_sample,
    compensator_step,
    demodulate,
    injection_sine,
)
from imdrive.kernels.compensator_range import injection_headroom, thermal_step
from imdrive.kernels.detection import stationary_mean_removed
from imdrive.kernels.flux_detector import detector_flux_error
from imdrive.kernels.gating import injection_frequency_Hz
from imdrive.kernels.jit import njit
from imdrive.kernels.model import incremental_L2


class TrackingInput(NamedTuple):
    """What the R2 law reads of the controller in one period (SI units)."""

    t: float  # the sample t_k, s
    t_cyc: float  # the duty cycle's time: t less the standstill test's hold, s
    k: int  # the sample's index since the start of the run
    sine: float  # the injection's sine this period (0 without the injection)
    w_ref: float  # the speed reference, mechanical rad/s
    w_fb: float  # the speed the gate compares with it, mechanical rad/s
    iq_torque: float  # iq* of the last period times the flux factor 1 - fw_cut, A
    v_use: float  # the last commanded voltage over Vdc_meas/sqrt 3
    w_e: float  # the controller's stator frequency, electrical rad/s
    w_sl: float  # the controller's slip frequency, electrical rad/s
    g_w: float  # the speed loop's gain over its rated-flux value
    iq_meas: float  # the controller's measured torque current (last control period), A
    Ts: float  # the control period, s


@njit(cache=True, inline="always")
def excitation(pk, cmp, t_cyc, v_use, k_flux, Ts):
    """The injection's sine and injected d-axis current of this period.

    Parameters
    ----------
    pk, cmp : the compensator's params and state records (``cmp``'s phase advanced)
    t_cyc : float
        The duty cycle's time, s.
    v_use : float
        The last commanded voltage over ``Vdc_meas/sqrt 3`` (the back-off near the limit).
    k_flux : float
        The field weakening's flux factor ``1 - fw_cut``.
    Ts : float
        The control period, s.

    Returns
    -------
    sine : float
        ``sin`` of the injection's phase (0 without the injection).
    i_inj : float
        ``a sine I_inj``, A, with ``a`` the headroom's back-off
        (:func:`~imdrive.kernels.compensator_range.injection_headroom`).
    """
    sine = 0.0
    i_inj = 0.0
    if pk.inj_amp != 0.0:
        ph0 = cmp.inj_phase
        sine = injection_sine(pk, cmp, t_cyc, Ts)
        a_inj = 1.0
        if pk.inj_v_hi > 0.0:  # the injection backs off near the voltage limit
            wrapped = cmp.inj_phase < ph0
            a_inj = injection_headroom(pk, cmp, v_use, k_flux, wrapped)
        i_inj = a_inj * pk.inj_amp * sine
    return sine, i_inj


@njit(cache=True, inline="always")
def track(pk, cmp, mdl, table, e_dq0, inp, w_r_hat, ti):
    """The detection, the gating and the law's decision after the estimator's step.

    Parameters
    ----------
    pk, cmp : the compensator's params and state records (``cmp`` updated)
    mdl : MODEL_STATE record
        The controller's model: the law writes ``R2_hat`` (and the thermal model its
        temperature).
    table : float64[13, 13]
        The fuzzy decision table.
    e_dq0 : complex
        The estimator's flux error in the controller's frame, Wb (unused where the detection
        forms its own, ``pk.det``).
    inp : EstimatorInput
        The estimator's input this period (the detection's own flux error reads it).
    w_r_hat : float
        The estimator's speed, electrical rad/s.
    ti : TrackingInput

    Returns
    -------
    complex
        The flux error the detection used, Wb.
    """
    if pk.det or pk.mean_out:  # a stage in the stationary frame
        rot = complex(math.cos(inp.theta_e), math.sin(inp.theta_e))
        if pk.det:  # the estimator gives no flux error: the detection forms its own
            e_ab = detector_flux_error(pk, cmp, mdl, inp, w_r_hat)
        else:
            e_ab = e_dq0 * rot
        if pk.mean_out:  # the sensors' offsets out (detection.py)
            w_i = 2.0 * math.pi * injection_frequency_Hz(pk, cmp)
            e_ab = stationary_mean_removed(cmp, e_ab, ti.w_e, w_i, pk.cpl_wc, ti.Ts)
        e_dq0 = e_ab * rot.conjugate()
    if pk.inj_amp != 0.0:
        T2_hat = incremental_L2(mdl) / mdl.R2_hat
        demodulate(pk, cmp, e_dq0, ti.sine, ti.w_e, ti.w_sl, T2_hat, ti.Ts)
    if pk.enabled:
        if ti.t_cyc >= pk.t_on and not cmp.on:  # its start, in the run's time (the metrics')
            cmp.on = True
            cmp.t_start = ti.t
        if pk.gate and ti.t_cyc >= pk.t_on:  # the compensator's gating signals
            compensator_gate_sample(
                pk, cmp, ti.w_ref, ti.w_fb, ti.iq_torque, ti.v_use, ti.w_e, ti.g_w
            )
        compensator_step(pk, cmp, mdl, table, e_dq0.real, ti.t_cyc, ti.k, ti.w_e)
        if pk.th_on:  # the rotor thermal model carries R2_hat while it is held
            thermal_step(pk, cmp, mdl, ti.iq_meas, ti.t_cyc, ti.Ts)
    return e_dq0
