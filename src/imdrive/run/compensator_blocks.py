"""The R2 compensator's records from the scenario: the injection, the detection (its own flux
error for an estimator that gives none), the gating and schedule, the step law (the fuzzy
table's or the model-based one's) and the rotor thermal model. Called by
:func:`imdrive.run.blocks.drive_records`; the rest of the drive's blocks are there.
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.config.compensator import demodulated_input
from imdrive.config.defaults import in_effect
from imdrive.config.injection_backoff import backoff_band
from imdrive.config.perunit import Resolved
from imdrive.config.r2_kalman import prior_pu
from imdrive.config.r2_laws import LawContext, plugin_law
from imdrive.config.registry import ESTIMATOR_SETTINGS
from imdrive.config.scenario import Scenario
from imdrive.config.validation import validate
from imdrive.errors import ConfigError
from imdrive.fuzzy import fuzzy_table
from imdrive.kernels.r2_law_registry import law_kernel
from imdrive.kernels.records import new_record

RPM = 2.0 * math.pi / 60.0  # rad/s per rpm


def compensator_fields(sc: Scenario, D: Resolved) -> tuple[dict, dict]:
    """``COMPENSATOR_PARAMS`` (fuzzy compensator, injection, gating, step law) and what to
    report; gains, clamps and amplitude absolute or in per-unit of the machine
    (:func:`imdrive.config.perunit.resolve`). The decision period ``D.n_comp`` holds whole
    injection periods (checked by the scenario:
    :func:`~imdrive.config.compensator.check_whole_injection_periods`)."""
    comp = sc.compensator
    inj = sc.injection
    r = D
    n_comp = D.n_comp
    t_on = tracking_start_s(sc)
    R2_min = in_effect(sc, "compensator.R2_min_ohm")
    R2_max = in_effect(sc, "compensator.R2_max_ohm")
    # the detection forms its own flux error (kernels/flux_detector.py): no estimator hands one
    det = comp.enabled and not gives_flux_error(sc.control.speed_feedback)
    record = dict(
        enabled=comp.enabled,
        t_on=t_on,
        n=n_comp,
        G_E=r.gain_E,
        G_DE=r.gain_DE,
        G_CR=r.G_CR,
        R2_min=R2_min,
        R2_max=R2_max,
        # the compensator reads it alone: off, the record is as it always was
        demodulated=comp.enabled and demodulated_input(inj, r),
        average=True,  # the window's mean, always (compensator.average: deprecated)
        inj_amp=r.inj_amp,
        inj_freq=r.inj_f1,
        inj_t_on=t_on,  # the injection starts with the compensator
        slip_decouple=inj.decouple_slip,
        cpl_wc=flux_filter_rad_s(sc),
        # the corner the injection's schedule keeps both side bands above (kernels/gating.py):
        # the detection's own filter; none where the MRAS family hands its error over, whose
        # speed adaptation closes its loop through that filter: there the band at its corner
        # measured worse (injection-fig5 at 54 rpm, 1.5 N m: R2_hat 2.7 % off at the third
        # harmonic against under 1 % at the second; the zero-frequency study's MRAS drive 47
        # converged of 84 against 50)
        sched_wc=flux_filter_rad_s(sc) if det else 0.0,
        cpl_wmin=2 * math.pi * sc.machine.rated_frequency_Hz * SLIP_DECOUPLING_FROM_PU,
        **_gating(sc, r),
        **_thermal(sc, D),
        **_kalman(sc, D),
        **_plugin(sc, D),
        det=det,
        # the error's stationary-frame mean removed (kernels/detection.py): on the error the
        # detection forms itself; the MRAS family's own is left as it was (the docstring of
        # stationary_mean_removed has what it measured there)
        mean_out=det and r.inj_amp != 0.0,
        **_detector_adaptation(sc, D),
    )
    derived = {
        "compensator_period_steps": n_comp,
        "R2_hat_min_ohm": R2_min,
        "R2_hat_max_ohm": R2_max,
    }
    return record, derived


def _detector_adaptation(sc: Scenario, D: Resolved) -> dict:
    """The detector's speed adaptation (kernels/flux_detector.py): Schauder's PI at the gains
    the MRAS of this drive would have (``det_K1``, ``det_K2``: its bandwidth, pole-zero
    cancellation at ``T2_hat``), held below the rated slip frequency while regenerating
    (``det_wmin``, electrical rad/s). Zero where the detection is not the law's."""
    from imdrive.config.rated import rated_point
    from imdrive.design.gains import default_mras_gains

    if not (sc.compensator.enabled and not gives_flux_error(sc.control.speed_feedback)):
        return {"det_K1": 0.0, "det_K2": 0.0, "det_wmin": 0.0}
    a = 2 * math.pi * in_effect(sc, "mras.bandwidth_Hz")
    T2_hat = (D.M_hat + D.Ll2_hat) / D.R2_hat
    K1, K2 = default_mras_gains(sc.machine.rated_flux_Wb, T2_hat, a)
    w_sl = 2 * math.pi * sc.machine.rated_frequency_Hz * rated_point(sc.machine).slip
    return {"det_K1": K1, "det_K2": K2, "det_wmin": w_sl}


def tracking_start_s(sc: Scenario) -> float:
    """When R2 tracking, the compensator and its injection, starts in the kernels' duty-cycle
    time, s: ``compensator.t_on_s`` moved by the premagnetisation's delay of the profiles
    (:func:`imdrive.config.sequence.sequence`, ``delay_s``), exactly as the speed reference and
    the load move; in the run, the standstill R1 test's wait holds it back with them too
    (``t_hold``, kernels/stages.py). No preset on Table IV is delayed (3 T2 = 0.26 s before
    their 0.5 s start): the same float as ``t_on_s`` there."""
    from imdrive.config.sequence import sequence

    return sc.compensator.t_on_s + sequence(sc).delay_s


#: The estimation headroom's integral gain per injection period (:func:`headroom_rate_per_s`):
#: Table IV's 1 /s at its 2 Hz injection, where the loop's gain per period times the voltage
#: use is 0.4 and it settles without overshoot (kernels/compensator_range.py,
#: headroom_weakening_input). It replaced two settings
#: (``injection.headroom_rate_per_s``, 1 /s, capped at ``headroom_gain_per_period`` 0.6 per
#: period): the cap, not the rate, acted on every machine with an injection below 1.67 Hz.
HEADROOM_GAIN_PER_PERIOD = 0.5

#: The slip decoupling of the detection (``injection.decouple_slip``) fades in from this
#: stator frequency, per-unit of the machine's rated one, to twice it: below, e_q0 is mostly the
#: voltage model's error (R1, the inverter: about 1/w_e), not the rotor's q flux
#: (kernels/compensator.py, demodulate). ``injection.decouple_slip_fmin_pu`` until round 8, at
#: this value in every preset, sweep and study; moving it by half either way (0.15, 0.45)
#: moved R2_hat's end by at most 0.04 % on injection-robust (Table IV, Aalto 2.2 kW, Krause
#: 50 hp; 0.1-2 x rated speed, rated motoring and regenerating load) and by one step of the
#: table law (2.45 %) either way at 0.3-0.5 x rated speed on injection-fig5-realistic's
#: bridge (better at 0.3 with 0.15, worse at 0.5 with 0.45): no value was better everywhere.
SLIP_DECOUPLING_FROM_PU = 0.3

#: Decision windows still held after a gated one (``compensator.gate_hold_periods`` until round
#: 4, the value every preset and study used): the flux and the MRAS settle after a speed or
#: load transient, a voltage limit or a switch of the injection frequency.
GATE_HOLD_PERIODS = 1


def headroom_rate_per_s(
    f_inj_Hz: float, gain_per_period: float = HEADROOM_GAIN_PER_PERIOD
) -> float:
    """The estimation headroom's integral gain in use, 1/s.

    Its slow term acts on the peak voltage use of the last whole injection period, held over
    the next one, so the flux factor ``k`` moves by the fraction ``rate T_inj (v_target -
    v_peak)`` of itself per period (the voltage use is nearly proportional to ``k`` above base
    speed, :func:`imdrive.kernels.compensator_range.headroom_weakening_input`) on a sample up
    to a period old: a sampled integral loop whose gain per period must stay below one.
    Table IV's 1 /s at 2 Hz is 0.5. The injection is set in per-unit of the rotor's
    corner frequency, 0.07-0.22 Hz on the large machines of the library, where 1 /s was
    4.5-14 per period: the flux cycled between rated and the field weakening's floor over tens of
    seconds (R2_hat 17 % off at no load on Krause 2250 hp), and from one stale peak (the
    load step's) it fell until the torque current saturated (Krause 500 hp, rated speed,
    regenerating: control lost).

    Parameters
    ----------
    f_inj_Hz : float
        The lowest injection frequency, Hz (its period is the longest the loop holds a sample).
    gain_per_period : float
        The gain per injection period (:data:`HEADROOM_GAIN_PER_PERIOD`).

    Returns
    -------
    float
        ``gain_per_period f_inj_Hz``, 1/s (1 /s on Table IV, 0.055 /s on Krause 2250 hp).
    """
    return gain_per_period * f_inj_Hz


def _gating(sc, r) -> dict:
    """The compensator's gating and frequency-schedule parameters (off: zeros)."""
    comp = sc.compensator
    on = in_effect(sc, "compensator.gating")
    out = {}
    inj = sc.injection
    # the amplitude backs off near the voltage limit whenever the field weakening is on
    # (injection.headroom, deprecated: config/compensator.py)
    headroom = in_effect(sc, "control.field_weakening")
    fw_v = sc.control.field_weakening_voltage
    if headroom and r.inj_amp > 0.0:
        # its band follows the voltage the field weakening holds (injection.headroom_from,
        # headroom_to: deprecated)
        out["inj_v_lo"], out["inj_v_hi"] = backoff_band(inj.headroom_voltage, fw_v)
    if inj.headroom_voltage is not None and r.inj_amp > 0.0:
        if not headroom:
            raise ConfigError("injection.headroom_voltage", "needs control.field_weakening = true")
        out |= {
            "inj_fw": True,
            "inj_v_peak": inj.headroom_voltage,
            "inj_fw_rate": headroom_rate_per_s(r.inj_f1),
            "fw_v": fw_v,
            "fw_rate": sc.control.field_weakening_rate,
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
        "gate_hold": float(GATE_HOLD_PERIODS),
        "inj_freq2": f2 if injecting and band > 0 else 0.0,
        "inj_freq3": r.inj_f3 if injecting and band > 0 else 0.0,
    }


def _thermal(sc, D: Resolved) -> dict:
    """The rotor thermal model's parameters (off: none); its thermal resistance in per-unit of
    the machine's rated rotor losses (:func:`~imdrive.config.perunit.rotor_thermal_resistance`).
    """
    comp = sc.compensator
    if not (comp.enabled and comp.thermal_model):
        return {}
    return {
        "th_on": True,
        "th_tau": comp.thermal_time_constant_s,
        "th_Rth": D.rotor_Rth,
        "th_alpha": comp.thermal_alpha_per_K,
    }


def gives_flux_error(speed_feedback: str) -> bool:
    """Whether the estimator ``speed_feedback`` runs hands the R2 detection a flux error
    (the MRAS family; ``"measured"`` runs the MRAS beside); otherwise the detection forms its
    own (:mod:`imdrive.kernels.flux_detector`)."""
    if speed_feedback == "measured":
        return True
    cls = ESTIMATOR_SETTINGS.get(speed_feedback)
    return cls is not None and bool(cls.estimator_flux_error)


def flux_filter_rad_s(sc: Scenario) -> float:
    """The corner of the ``1/(s + wc)`` filter behind the flux error the detection reads,
    rad/s: the running estimator's own (``wc_rad_s`` of its section: the MRAS's, the
    sliding-mode MRAS's) where it hands the detection its flux error, else the detector's
    (:mod:`imdrive.kernels.flux_detector`, Schauder's two models, built with ``[mras]
    wc_rad_s``). The slip decoupling undoes this filter. Until 2026-11-29 ``[mras]
    wc_rad_s`` was read for every estimator: a sliding-mode MRAS with its own ``wc_rad_s``
    had its flux error decoupled with the MRAS's filter."""
    fb = sc.control.speed_feedback
    if fb != "measured" and gives_flux_error(fb):
        wc = getattr(sc.estimator_settings(), "wc_rad_s", None)
        if wc is not None:
            return float(wc)
    return sc.mras.wc_rad_s


def _kalman(sc, D: Resolved) -> dict:
    """The model-based law's parameters (``compensator.step_law = "kalman"``; off: none):
    its noise levels relative to R2 (section ``[kalman]``), R̂2(0) and the decision period."""
    if sc.compensator.step_law != "kalman":
        return {}
    k = sc.kalman
    return {
        "kf": True,
        "kf_r": k.noise_pu,
        "kf_q": k.drift_pu,
        "kf_p0": prior_pu(sc),
        "kf_R2": D.R2_hat,
        "kf_T": D.n_comp * sc.simulation.Ts_s,
    }


def _plugin(sc, D: Resolved) -> dict:
    """A plug-in law's flag and decision period (``compensator.step_law`` names one)."""
    if not sc.compensator.enabled or plugin_law(sc.compensator.step_law) is None:
        return {}
    return {"plugin": True, "kf_T": D.n_comp * sc.simulation.Ts_s}


def plugin_law_kernel(sc: Scenario):
    """The compiled half of the plug-in law ``compensator.step_law`` names, or None (one of
    the package's laws, or no compensator: the stability maps' drive, one compiled map for
    every law)."""
    name = sc.compensator.step_law
    if not sc.compensator.enabled or plugin_law(name) is None:
        return None
    try:
        return law_kernel(name)
    except KeyError:
        raise ConfigError(
            "compensator.step_law",
            f'"{name}" has settings but no kernel: its module must call '
            "imdrive.kernels.r2_law_registry.register_law",
        ) from None


def law_slot(sc: Scenario, D: Resolved):
    """The plug-in law's compiled half and its records for the compensator's ``law`` slot.

    Returns
    -------
    tuple
        ``(kernel, params, state)``: the :class:`~imdrive.kernels.r2_law_registry.LawKernel`
        and ``(1,)`` records of its dtypes, built by its settings class's ``records`` from
        its ``[plugins.settings.NAME]`` table; ``(None, None, None)`` for the package's laws
        and without a compensator (:func:`plugin_law_kernel`).
    """
    kernel = plugin_law_kernel(sc)
    if kernel is None:
        return None, None, None
    name = kernel.name
    own = validate(plugin_law(name), sc.plugins.settings.get(name, {}), f"plugins.settings.{name}")
    ctx = LawContext(
        scenario=sc,
        R2_hat=D.R2_hat,
        T=D.n_comp * sc.simulation.Ts_s,
        R2_min=D.R2_min,
        R2_max=D.R2_max,
    )
    recs = own.records(ctx)
    try:
        return kernel, new_record(kernel.params, recs.params), new_record(kernel.state, recs.state)
    except KeyError as exc:
        raise ConfigError(f"plugins.settings.{name}", f"its records: {exc.args[0]}") from None


def fuzzy_lookup_table(sc: Scenario) -> np.ndarray:
    """The compensator's 13 x 13 lookup table (``compensator.table``)."""
    return fuzzy_table(sc.compensator.table).astype(np.float64)
