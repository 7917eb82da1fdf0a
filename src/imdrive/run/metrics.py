"""Every metric of a run, defined once.

Three families, each used by the CLI, the batch, the sweeps and the paper's study alike:

* :func:`drive_metrics` — one row per drive, the columns of the batch and sweep tables. The
  batch kernel (:mod:`imdrive.kernels.batch`) computes the same quantities while the samples
  stream past; ``tests/run/test_batch.py`` checks the two agree to 1e-12.
* :func:`compensation_metrics` — how the R2 compensator did (``summary.json``, the paper's
  compensation table).
* :func:`steady_means` — means of the main signals over the last part of a run (the paper's
  e_d0 experiments).

Definitions of :func:`drive_metrics`
------------------------------------
All are computed from the full-rate samples ``k = 0 ... K`` (``K = n_steps`` for a complete run,
``t_k = k Ts``), i.e. the rows a ``simulate()`` with ``log_every = 1`` logs. Speeds are
mechanical, in rpm; ``speed`` is the plant's, ``speed_ref`` the reference (0 in open loop),
``speed_est`` the MRAS estimate (0 in open loop, the measured-speed drives also run the MRAS).
The *window* is the samples ``k >= n_steps - round(window_s / Ts)`` (the last ``window_s``
seconds, both ends included; the whole run if ``window_s >= t_end``), cut to start where the
last change of the speed reference or the load has settled (:func:`settled_at_s`) when at
least a fifth of it is left (:func:`steady_window_periods`; the status says when it was not).

``speed_error_rpm``      mean of ``speed - speed_ref`` over the window
``speed_est_error_rpm``  mean of ``speed_est - speed`` over the window
``speed_ripple_rpm``     ``max(speed) - min(speed)`` over the window
``torque_mean_Nm``       mean electromagnetic torque over the window
``R2_hat_final_ohm``     the rotor-resistance estimate at the last sample
``R2_final_ohm``         the plant's rotor resistance at the last sample (scale and temperature)
``R2_error_pct``         ``100 (R2_hat - R2) / R2`` at the last sample
``convergence_time_s``   the first sample time after which ``|R2_hat - R2| / R2 <= 2 %`` at
                         every sample to the end (``R2`` the plant's at each sample): 0 if it
                         holds throughout, NaN if it does not hold at the last sample
``peak_current_A``       ``max sqrt(i_alpha^2 + i_beta^2)`` of the plant's stator current over
                         all samples
``final_speed_rpm``, ``final_speed_ref_rpm``, ``final_speed_est_rpm``   at the last sample
``lost_control_at_s``    loss of control: the time of the first sample of the first
                         *departure* (a run of consecutive samples with
                         ``|speed - speed_ref| > simulation.lost_control_rpm``) that lasts
                         ``simulation.lost_control_s`` or longer (its last sample time minus
                         its first); NaN if there is none. Checked only in vector control with
                         a free speed (not ``plant.speed_mode = "imposed"``) and a bound > 0.
                         Also on the samples of a diverged run before the divergence.
                         A sample that follows its reference at the torque limit (the torque
                         current at the current limit, pushing towards the reference, the
                         speed moving towards it: :func:`torque_limited`) is not counted in a
                         departure's length (a ramp or step the machine cannot follow faster
                         is not a loss of control), nor does it end the departure (a drive
                         out of control swings back at the limit too)
``torque_limited_s``     how long the speed was out of that band while following at the
                         torque limit (before any loss of control), s
``lost_control``         ``lost_control_at_s`` is not NaN (a boolean column)
``R1_id_status``         the standstill R1 identification's last outcome (``mras.R1_standstill``,
                         the log column ``R1_id_status_code`` at the last sample): 0 no
                         standstill run, 1 identified, 2 could not, 3 one level of two
                         (NaN without the MRAS);
                         the batch takes it from the final state
``R2_held_pct``          share of the samples from the compensator's start
                         (:func:`compensator_start_s`) at which R2_hat was held, i.e. the
                         gating mask ``comp_frozen`` of the last decision was not 0, % (NaN
                         without a compensator)
``R2_held_causes``       OR of those masks (the bits of :mod:`imdrive.kernels.compensator`)
``R2_held_since_s``      when R2_hat is held at the last sample: the first sample time of that
                         uninterrupted held stretch; NaN if it was being estimated at the end
``R2_held_end_causes``   OR of the masks over that stretch (0 if none)
``R2_error_window_pct``  the ``100 (R2_hat - R2) / R2`` of largest magnitude over the window,
                         with its sign: whether R2_hat had settled (an R2_hat that swings may
                         end inside the tolerance by phase)

plus the status columns of :mod:`imdrive.run.status` (``speed_error_pu_slip``,
``speed_tolerance_rpm``, ``verdict``, ``verdict_text``, ``verdict_at_s``), ``status`` (0 ok,
else the divergence code of :mod:`imdrive.kernels.engine`), ``diverged``,
``diverged_at_s`` (the time the divergence was found, ``k_end Ts``; NaN if not diverged) and
``simulated_s`` (``k_end Ts``). For a diverged drive the samples are those logged before the
divergence: the window metrics and ``convergence_time_s`` are NaN (no steady state was reached),
the final values and ``peak_current_A`` are those of the last sample before the divergence.
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.config.perunit import lost_control_rpm
from imdrive.config.sequence import (
    DEFAULT_WINDOW_S,
    MIN_SETTLED_SHARE,
    sequence,
    settled_at_s,
)
from imdrive.errors import check_number
from imdrive.kernels.batch import CONVERGENCE_BAND, METRICS
from imdrive.run.columns import Metrics

__all__ = [
    "CONVERGENCE_BAND",
    "DEFAULT_WINDOW_S",
    "METRICS",
    "compensation_metrics",
    "drive_metrics",
    "lost_control_check",
    "lost_control_at",
    "lost_control_rule",
    "lost_control_time",
    "torque_limited",
    "steady_means",
]


def lost_control_check(scenario) -> tuple[float, float]:
    """``(bound, duration)`` of the loss-of-control check: rad/s (0: off) and s."""
    sim = scenario.simulation
    bound = lost_control_rpm(scenario)
    on = scenario.drive.mode == "vector" and scenario.plant.speed_mode != "imposed" and bound > 0
    return (bound * math.pi / 30.0 if on else 0.0), sim.lost_control_s


def lost_control_rule(scenario) -> str:
    """One line saying how loss of control is checked in ``scenario``: the bound of
    :func:`~imdrive.config.perunit.lost_control_rpm` (derived from the machine unless the
    scenario sets ``simulation.lost_control_rpm``) and ``simulation.lost_control_s``."""
    sim = scenario.simulation
    bound, _ = lost_control_check(scenario)
    if bound == 0.0:
        return "loss of control not checked (open loop, imposed speed, or a bound of 0)"
    how = (
        "set in the scenario"
        if sim.lost_control_rpm is not None
        else "twice the machine's rated slip, at least 1 % of its rated speed"
    )
    return (
        f"loss of control: the speed more than {lost_control_rpm(scenario):.3g} rpm from its "
        f"reference for {sim.lost_control_s:g} s or longer (simulation.lost_control_rpm: {how})"
    )


def torque_limited(s: dict, i_max_A: float) -> np.ndarray:
    """Which logged samples follow their speed reference at the torque limit, a boolean array:
    :func:`imdrive.kernels.batch.at_torque_limit` on the signals ``s`` (``speed_rpm``,
    ``speed_ref_rpm``, ``id_ref_A``, ``iq_ref_A``; all False without them)."""
    n = len(s["time_s"])
    if i_max_A <= 0.0 or not {"speed_ref_rpm", "id_ref_A", "iq_ref_A"} <= set(s):
        return np.zeros(n, dtype=bool)
    w, ref = np.asarray(s["speed_rpm"]), np.asarray(s["speed_ref_rpm"])
    e = ref - w
    prev = np.concatenate(([np.nan], w[:-1]))
    i_d, i_q = np.asarray(s["id_ref_A"]), np.asarray(s["iq_ref_A"])
    iq_max = np.sqrt(np.maximum(i_max_A * i_max_A - i_d * i_d, 0.0))
    with np.errstate(invalid="ignore"):
        return (np.abs(i_q) >= 0.999 * iq_max) & (i_q * e > 0.0) & ((w - prev) * e > 0.0)


def lost_control_at(res) -> tuple[float, float]:
    """``(lost_control_at_s, torque_limited_s)`` of a run: its first loss of control (NaN if
    none) and how long it followed its speed reference at the torque limit, out of the band,
    s (:func:`lost_control_time` with :func:`torque_limited`)."""
    sc, s = res.scenario, res.signals
    bound, duration = lost_control_check(sc)
    if "speed_ref_rpm" not in s or bound == 0.0:
        return math.nan, 0.0
    from imdrive.config.perunit import resolve

    limited = torque_limited(s, resolve(sc).current_limit_A)
    args = (s["time_s"], s["speed_rpm"], s["speed_ref_rpm"], bound * 30.0 / math.pi)
    out = np.abs(s["speed_rpm"] - s["speed_ref_rpm"]) > args[3]
    t_lc = lost_control_time(*args, duration, limited)
    t = np.asarray(s["time_s"])
    k = np.flatnonzero(out & limited)
    if math.isfinite(t_lc):
        k = k[t[k] < t_lc]  # as the batch kernel counts: until the loss of control
    dt = t[1] - t[0] if len(t) > 1 else sc.simulation.Ts_s
    return t_lc, float(len(k) * dt)


def lost_control_time(
    time_s, speed_rpm, speed_ref_rpm, bound_rpm, duration_s, limited=None
) -> float:
    """Start of the first departure of ``speed`` from ``speed_ref`` by more than ``bound_rpm``
    lasting ``duration_s`` or longer, s (NaN if none; see the module docstring). In a
    departure where the speed only heads for its reference (a lag: it never falls back from
    its closest approach by ``bound_rpm``), the samples of ``limited`` (boolean,
    :func:`torque_limited`) are not counted in its length (the sample spacing each); in any
    other (a stall, a runaway, a swing out of control) every sample counts, as
    :func:`imdrive.kernels.batch.accumulate` counts them."""
    if bound_rpm <= 0.0 or len(time_s) == 0:
        return math.nan
    t = np.asarray(time_s)
    w = np.asarray(speed_rpm)
    e = np.asarray(speed_ref_rpm) - w
    out = np.abs(e) > bound_rpm
    if not out.any():
        return math.nan
    # runs of consecutive out-of-band samples: their first and last indices
    d = np.diff(np.concatenate(([0], out.astype(np.int8), [0])))
    first = np.flatnonzero(d == 1)
    last = np.flatnonzero(d == -1) - 1
    for a, b in zip(first, last, strict=True):
        length = t[b] - t[a]
        if length < duration_s - 1e-12:
            continue
        if limited is not None and len(t) > 1:
            toward = np.sign(e[a]) * w[a : b + 1]  # the speed towards the reference
            if np.all(np.maximum.accumulate(toward) - toward <= bound_rpm):  # a lag
                length -= np.count_nonzero(limited[a : b + 1]) * (t[1] - t[0])
        if length >= duration_s - 1e-12:
            return float(t[a])
    return math.nan


def steady_window_periods(sc, window_s: float, Ts: float, n_steps: int) -> int:
    """Control periods in the steady-state window of scenario ``sc``: the last ``window_s``
    (:func:`window_periods`), cut to start where the last transient has settled
    (:func:`settled_at_s`) when at least :data:`MIN_SETTLED_SHARE` of it is left; else whole
    (and :func:`imdrive.run.status.verdict` says the run had not settled)."""
    n = window_periods(window_s, Ts, n_steps)
    left = n_steps - int(math.ceil(settled_at_s(sc) / Ts - 1e-9))
    if left < n and left >= MIN_SETTLED_SHARE * n:
        return left
    return n


def window_periods(window_s: float, Ts: float, n_steps: int) -> int:
    """Control periods in the steady-state window: ``round(window_s / Ts)``, at most the run's
    ``n_steps`` (a window longer than the run is the whole run, however long it is given)."""
    return int(round(min(window_s / Ts, n_steps)))


def drive_metrics(res, window_s: float = DEFAULT_WINDOW_S) -> dict:
    """The batch table's row of one run (definitions in the module docstring).

    Exact (equal to the batch to rounding) for a run logged at every period
    (``simulation.log_every = 1``); with decimated logs the same formulas apply to the logged
    samples, so window means, peaks and the convergence time are those of the decimated signal.

    Parameters
    ----------
    res : SimulationResult
    window_s : float
        Length of the steady-state window, s.

    Returns
    -------
    dict
        ``status``, ``diverged``, ``diverged_at_s``, ``simulated_s`` and every name of
        :data:`METRICS`.
    """
    window_s = check_number(window_s, "window_s", lo=0.0)  # a negative one: NaN means
    s = res.signals
    sc = res.scenario
    Ts = sc.simulation.Ts_s
    n_steps = sequence(sc).n_steps(Ts)
    k = np.rint(s["time_s"] / Ts).astype(np.int64)
    ok = not res.diverged
    nan = math.nan
    out = {
        "status": res.status,
        "diverged": res.diverged,
        "diverged_at_s": res.k_end * Ts if res.diverged else nan,
        "simulated_s": res.k_end * Ts,
    }
    zeros = np.zeros(len(k))
    speed = s["speed_rpm"]
    speed_ref = s.get("speed_ref_rpm", zeros)
    speed_est = s.get("speed_est_rpm", zeros)
    R2_hat = s.get("R2_hat_ohm", s["R2_ohm"])
    win = k >= n_steps - steady_window_periods(sc, window_s, Ts, n_steps)
    rel = np.abs(R2_hat - s["R2_ohm"]) / s["R2_ohm"]
    bad = np.flatnonzero(~(rel <= CONVERGENCE_BAND))
    if not ok:
        conv = nan
    elif bad.size == 0:
        conv = 0.0
    elif bad[-1] == len(k) - 1:
        conv = nan
    else:
        conv = float(s["time_s"][bad[-1] + 1])
    steady = ok and win.any()
    out.update(
        {
            "speed_error_rpm": np.mean(speed[win] - speed_ref[win]) if steady else nan,
            "speed_est_error_rpm": np.mean(speed_est[win] - speed[win]) if steady else nan,
            "speed_ripple_rpm": np.ptp(speed[win]) if steady else nan,
            "torque_mean_Nm": np.mean(s["torque_Nm"][win]) if steady else nan,
            "R2_error_window_pct": _window_peak_pct(R2_hat[win], s["R2_ohm"][win])
            if steady
            else nan,
            "R2_hat_final_ohm": R2_hat[-1],
            "R2_final_ohm": s["R2_ohm"][-1],
            "R2_error_pct": 100 * (R2_hat[-1] - s["R2_ohm"][-1]) / s["R2_ohm"][-1],
            "convergence_time_s": conv,
            "peak_current_A": np.max(np.sqrt(s["i_alpha_A"] ** 2 + s["i_beta_A"] ** 2)),
            "final_speed_rpm": speed[-1],
            "final_speed_ref_rpm": speed_ref[-1],
            "final_speed_est_rpm": speed_est[-1],
        }
    )
    # the standstill R1 identification's last outcome (0 none, 1 identified, 2 could not)
    out["R1_id_status"] = float(s["R1_id_status_code"][-1]) if "R1_id_status_code" in s else nan
    t_lc, t_limited = lost_control_at(res)
    out["lost_control"] = not math.isnan(t_lc)
    out["lost_control_at_s"] = t_lc
    out["torque_limited_s"] = t_limited
    out.update(held_metrics(res))
    from imdrive.run.status import verdict

    out.update(verdict(sc, out | {"window_s": window_s}))
    return out


def _window_peak_pct(R2_hat, R2) -> float:
    """The relative R2 error of largest magnitude over the window, with its sign, %."""
    e = (R2_hat - R2) / R2
    return float(100.0 * e[np.argmax(np.abs(e))])


def compensator_start_s(res) -> float:
    """When the R2 compensator started in the run's time, s (``inf``: it never did).

    ``compensator.t_on_s`` is a time of the duty cycle: the drive moves it with the speed and
    load profiles, by the premagnetisation's delay and the standstill R1 test's wait
    (:func:`imdrive.run.compensator_blocks.tracking_start_s`, kernels/stages.py). The kernels
    record where it fell (``COMPENSATOR_STATE.t_start``); a result without its final state
    (a stand-in) falls back on the configured start moved by the premagnetisation's delay.
    """
    comp = res.scenario.compensator
    if not comp.enabled:
        return math.inf
    state = getattr(res, "state_final", None)
    if state is not None and "on" in state.comp.dtype.names:
        c = state.comp[0]
        return float(c["t_start"]) if c["on"] else math.inf
    from imdrive.run.compensator_blocks import tracking_start_s

    return tracking_start_s(res.scenario)


def held_metrics(res) -> dict:
    """``R2_held_pct``, ``R2_held_causes``, ``R2_held_since_s``, ``R2_held_end_causes`` of a
    run (module docstring), from its logged gating mask."""
    nan = math.nan
    comp = res.scenario.compensator  # as the drive's COMPENSATOR_PARAMS enabled, t_on
    s = res.signals
    t = s["time_s"]
    if not comp.enabled or "comp_frozen_flags" not in s:
        active = np.zeros(len(t), dtype=bool)
    else:
        active = t >= compensator_start_s(res)
    if not active.any():
        return dict.fromkeys(
            ("R2_held_pct", "R2_held_causes", "R2_held_since_s", "R2_held_end_causes"), nan
        )
    flags = s["comp_frozen_flags"][active].astype(np.int64)
    held = flags != 0
    causes = int(np.bitwise_or.reduce(flags)) if len(flags) else 0
    if held[-1]:
        upd = np.flatnonzero(~held)
        first = upd[-1] + 1 if upd.size else 0
        since = float(t[active][first])
        end = float(np.bitwise_or.reduce(flags[first:]))
    else:
        since, end = nan, 0.0
    return {
        "R2_held_pct": 100.0 * held.sum() / len(held),
        "R2_held_causes": float(causes),
        "R2_held_since_s": since,
        "R2_held_end_causes": end,
    }


def _settling_with_its_event(flags: np.ndarray, settling: int = 16) -> np.ndarray:
    """Each sample's gating mask with a settling-only hold (``settling`` alone) given the bits
    of the last event before it (the gating settles after the event's own bit clears)."""
    event = flags & ~settling
    last = np.maximum.accumulate(np.where(event != 0, np.arange(flags.size), -1))
    owner = np.where(last >= 0, event[np.maximum(last, 0)], 0)
    return np.where(flags == settling, flags | owner, flags)


def held_shares(res) -> dict[str, float]:
    """The share of time R̂2 was held for each cause, % of the samples from the compensator's
    enable time (``t >=`` its start, :func:`compensator_start_s`), by the groups of
    :data:`imdrive.run.status.HELD_CAUSES` (a sample held for two causes counts in both; a
    settling bit, 16, counts with the event it follows, as in
    :func:`imdrive.run.status.held_reasons`, also once the event's own bit has cleared: the
    settling after the injection's start is the start's, not a transient). Empty without a
    compensator or when R̂2 was never held."""
    from imdrive.run.status import held_reasons

    comp = res.scenario.compensator
    s = res.signals
    if not comp.enabled or "comp_frozen_flags" not in s:
        return {}
    active = s["time_s"] >= compensator_start_s(res)
    flags = _settling_with_its_event(s["comp_frozen_flags"].astype(np.int64))[active]
    if not flags.size:
        return {}
    masks, counts = np.unique(flags[flags != 0], return_counts=True)
    shares: dict[str, float] = {}
    for mask, n in zip(masks, counts, strict=True):
        for group in held_reasons(int(mask)):
            shares[group] = shares.get(group, 0.0) + 100.0 * n / flags.size
    return dict(sorted(shares.items(), key=lambda kv: -kv[1]))


def r1_sensitivity(res, window_s: float = DEFAULT_WINDOW_S) -> float | None:
    """How far an R1_hat error moves R2_hat at the run's final operating point: ``g`` of
    :func:`imdrive.analysis.observability.r2_r1_sensitivity` (R2_hat's relative change per
    relative R1_hat error) from the means over the last ``window_s`` of the controller's
    stator frequency (the slope of ``theta_e``), the stator current ``|i_dq|``, the rotor
    flux and the final R1_hat. None without a compensator or a diverged run; ``inf`` at zero
    stator frequency."""
    s = res.signals
    if not res.scenario.compensator.enabled or res.diverged or "theta_e_rad" not in s:
        return None
    # here, not above: the analysis package imports scipy.optimize (0.3 s of a warm run)
    from imdrive.analysis.observability import r2_r1_sensitivity
    from imdrive.config.perunit import resolve

    t = s["time_s"]
    win = t >= t[-1] - window_s
    if win.sum() < 2:
        return None
    theta = np.unwrap(s["theta_e_rad"][win])
    w_e = (theta[-1] - theta[0]) / (t[win][-1] - t[win][0])
    i_s = float(np.mean(np.hypot(s["i_d_A"][win], s["i_q_A"][win])))
    psi = float(np.mean(s["flux_Wb"][win]))
    D = resolve(res.scenario)
    R1 = float(s["R1_hat_ohm"][-1]) if "R1_hat_ohm" in s else D.R1_hat
    return r2_r1_sensitivity(R1, D.M_hat, D.M_hat + D.Ll2_hat, i_s, w_e, psi)


def compensation_metrics(
    res, tol: float = CONVERGENCE_BAND, window_s: float = DEFAULT_WINDOW_S
) -> dict | None:
    """How the R2 compensator did (None when it is off).

    ``time_to_tolerance_s``: time from the compensator's enable instant after which
    ``|R2_hat/R2 - 1| <= tol`` holds to the end of the run (None if it never settles
    there). Speed errors (actual minus reference, rpm) are means over ``window_s`` just
    before the enable instant and at the end of the run; the ripple is the peak-to-peak
    actual speed over the final window. The ``R2_hat_*`` keys were ``R2_est_*`` before the
    naming glossary; the old keys still answer, with a ``DeprecationWarning``
    (:class:`~imdrive.run.columns.Metrics`).
    """
    window_s = check_number(window_s, "window_s", lo=0.0)
    tol = check_number(tol, "tol", lo=0.0)
    comp = res.scenario.compensator
    if not comp.enabled or res.scenario.drive.mode != "vector" or len(res.time_s) < 2:
        return None
    s = res.signals
    t = s["time_s"]
    t_on = compensator_start_s(res)
    ratio_err = np.abs(s["R2_hat_ohm"] / s["R2_ohm"] - 1.0)
    outside = np.nonzero((ratio_err > tol) | (t < t_on))[0]
    if len(outside) == 0:
        t_tol = 0.0
    elif outside[-1] + 1 < len(t):
        t_tol = float(t[outside[-1] + 1] - t_on)
    else:
        t_tol = None
    before = (t >= t_on - window_s) & (t < t_on)
    after = t >= t[-1] - window_s
    err = s["speed_rpm"] - s["speed_ref_rpm"]
    return Metrics(
        {
            "R2_ohm": float(s["R2_ohm"][-1]),
            "R2_hat_initial_ohm": float(s["R2_hat_ohm"][0]),
            "R2_hat_final_ohm": float(s["R2_hat_ohm"][-1]),
            "R2_hat_final_error_pct": float(100.0 * (s["R2_hat_ohm"][-1] / s["R2_ohm"][-1] - 1)),
            "tolerance_pct": 100.0 * tol,
            "time_to_tolerance_s": t_tol,
            "speed_error_before_rpm": float(np.mean(err[before])) if before.any() else None,
            "speed_error_after_rpm": float(np.mean(err[after])),
            "speed_ripple_after_rpm": float(np.ptp(s["speed_rpm"][after])),
            "e_d0_mean_after_Wb": float(np.mean(s["e_d0_Wb"][after])),
        }
    )


def steady_means(res, window_s: float = DEFAULT_WINDOW_S) -> dict:
    """Means over the last ``window_s`` of a vector-controlled run (the paper's experiments)."""
    window_s = check_number(window_s, "window_s", lo=0.0)
    w = res.window(res.time_s[-1] - window_s)
    return {
        "e_d0_Wb": float(np.mean(w["e_d0_Wb"])),
        "e_q0_Wb": float(np.mean(w["e_q0_Wb"])),
        "speed_error_rpm": float(np.mean(w["speed_rpm"] - w["speed_ref_rpm"])),
        "speed_est_error_rpm": float(np.mean(w["speed_est_rpm"] - w["speed_rpm"])),
        "flux_Wb": float(np.mean(w["flux_Wb"])),
        "torque_Nm": float(np.mean(w["torque_Nm"])),
    }
