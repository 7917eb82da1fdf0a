"""What went wrong first in a run, in one line for the console (``imdrive run``).

A run that loses control and later diverges is reported by its first event (the loss of
control), with what moved first (the speed estimate away from the actual speed, or the actual
speed away from its reference), where to look, and, when the scenario's own numbers explain
it, which setting is the likely cause: a speed loop too slow for the machine's inertia lets a
load step pull the speed further than the loss-of-control bound. A run that completed but
whose status (:mod:`imdrive.run.status`) is not ok gets a line too: its causes in time order
(R̂2 frozen or held and why, R̂2 off, the speed error beyond its tolerance).

The speed loop (IFOC, :func:`imdrive.design.gains.default_speed_gains`) with the plant
``J p w = k_t i_q - T_L`` and the PI ``i_q = kp e + ki ∫e`` answers a load step ``ΔT_L`` with

    w(s) = -ΔT_L / (J s² + k_t kp s + k_t ki),

an impulse response of a second-order system; :func:`load_step_dip_rpm` is its peak. For the
default gains (``kp = J a / k_t``, ``ki = kp a / 4``, ``a = 2π speed_bandwidth_Hz``) the poles
are double at ``-a/2`` and the peak is ``2 ΔT_L / (e J a)``.
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.config.perunit import lost_control_rpm, speed_bandwidth_Hz
from imdrive.config.sequence import sequence


def load_step_dip_rpm(J: float, k_t: float, kp: float, ki: float, step_Nm: float) -> float:
    """Peak speed deviation after a load-torque step, rpm (mechanical; current not limited).

    Parameters
    ----------
    J : float
        Inertia, kg m².
    k_t : float
        Torque constant of the controller, N m / A.
    kp, ki : float
        Speed PI gains, A/(rad/s) and A/rad.
    step_Nm : float
        Size of the load step, N m.

    Returns
    -------
    float
        ``max_t |w(t)|`` of the step response (module docstring), rpm.
    """
    from scipy import signal

    b, c = k_t * kp, k_t * ki
    # the slowest time constant sets the horizon of the response
    poles = np.roots([J, b, c])
    slow = min(abs(p.real) for p in poles if p.real != 0) if c > 0 else b / J
    t = np.linspace(0.0, 12.0 / max(slow, 1e-6), 4000)
    _, y = signal.impulse(([1.0], [J, b, c]), T=t)
    return float(abs(step_Nm) * np.max(np.abs(y)) * 30.0 / math.pi)


def _steepest_ramp_rad_s2(profile) -> float:
    """The steepest slope of a piecewise-linear speed profile, mechanical rad/s²."""
    pts = profile.points
    slopes = [
        abs(v1 - v0) / (t1 - t0)
        for (t0, v0), (t1, v1) in zip(pts, pts[1:], strict=False)
        if t1 > t0
    ]
    return max(slopes, default=0.0) * math.pi / 30.0


def _largest_load_step(scenario) -> float:
    values = [v for _, v in sequence(scenario).load_Nm.points]
    steps = np.abs(np.diff(values)) if len(values) > 1 else np.zeros(1)
    return float(max(steps.max(initial=0.0), abs(values[0]) if values else 0.0))


def tuning_hint(res) -> str | None:
    """The likely setting behind a loss of control, or None: the speed loop's bandwidth
    against the inertia and the largest load step (module docstring)."""
    sc = res.scenario
    d = res.derived
    if sc.drive.mode != "vector" or not {"speed_kp", "speed_ki"} <= set(d):
        return None
    k_t = d.get("torque_constant_Nm_per_A")
    if not k_t:
        return None
    J = sc.machine.J_kgm2
    i_max, psi = d.get("current_limit_A"), d.get("flux_ref_Wb")
    if i_max and psi:  # the ramp's acceleration torque against what the current limit allows
        i_d = psi / (sc.machine.M_H or 1.0)
        t_max = k_t * math.sqrt(max(i_max**2 - i_d**2, 0.0))
        seq = sequence(sc)
        loads = [abs(v) for _, v in seq.load_Nm.points]
        need = J * _steepest_ramp_rad_s2(seq.speed_ref_rpm) + max(loads, default=0.0)
        if need > t_max:
            return (
                f"likely cause: the speed ramp asks for {need:.3g} N m (J = {J:g} kg m2 "
                f"accelerating, with the load), the current limit allows {t_max:.3g} N m: a "
                "slower ramp (control.speed_ref_rpm) or a higher control.current_limit_A"
            )
    step = _largest_load_step(sc)
    if step <= 0.0:
        return None
    dip = load_step_dip_rpm(J, k_t, d["speed_kp"], d["speed_ki"], step)
    bound = lost_control_rpm(sc)
    if dip <= 0.5 * bound:
        return None
    ctl = sc.control
    if ctl.speed_kp is None:
        gains = f"control.speed_bandwidth_Hz = {speed_bandwidth_Hz(sc):.3g} Hz"
        if ctl.speed_bandwidth_Hz is None:
            gains += ", derived from the machine"
    else:
        gains = f"control.speed_kp = {ctl.speed_kp:g}"
    return (
        f"likely cause: the speed loop ({gains}) is slow for J = {J:g} kg m2: the "
        f"{step:g} N m load step moves the speed by about {dip:.0f} rpm "
        f"(loss-of-control bound {bound:.3g} rpm); raise control.speed_bandwidth_Hz"
    )


def _what_moved(res, t0: float) -> str:
    """What left its reference first, in the window after ``t0``."""
    s = res.signals
    if "speed_est_rpm" not in s or "speed_ref_rpm" not in s:
        return ""
    duration = max(res.scenario.simulation.lost_control_s, 1e-3)
    m = (s["time_s"] >= t0) & (s["time_s"] <= t0 + duration)
    if not m.any():
        return ""
    est = float(np.nanmean(np.abs(s["speed_est_rpm"][m] - s["speed_rpm"][m])))
    ref = float(np.nanmean(np.abs(s["speed_rpm"][m] - s["speed_ref_rpm"][m])))
    if est > 0.5 * ref:
        return (
            f"the speed estimate left the actual speed ({est:.0f} rpm apart on average): "
            "the estimator"
        )
    return (
        f"the speed left its reference ({ref:.0f} rpm) while the estimate followed it: "
        "the speed loop (torque, current or voltage limit, tuning)"
    )


def _verdict(res) -> dict | None:
    """The run's status (:attr:`SimulationResult.verdict`), None for a stand-in without one."""
    try:
        return res.verdict
    except (AttributeError, KeyError):
        return None


#: where to look when a run's folder holds none of the plots: its data, the first found
DATA_FILES = ("timeseries.csv", "timeseries.parquet", "timeseries.mat", "summary.json")


def _where(out, files: tuple[str, ...]) -> str:
    """Those of ``files`` that the folder ``out`` holds, ``"a, b and c in OUT"`` (the PNG
    figures are written only when asked), else its time series (:data:`DATA_FILES`);
    ``"res.plot()"`` without a folder or with none of them."""
    if out is None:
        return "res.plot()"
    from pathlib import Path

    there = [f for f in files if (Path(out) / f).is_file()]
    there = there or [f for f in DATA_FILES if (Path(out) / f).is_file()][:1]
    if not there:
        return "res.plot()"
    names = there[0] if len(there) == 1 else f"{', '.join(there[:-1])} and {there[-1]}"
    return f"{names} in {out}"


def closing_line(res, out=None) -> str | None:
    """The console's last line for a run that diverged or lost control, or None.

    Parameters
    ----------
    res : SimulationResult
        The run.
    out : str or pathlib.Path, optional
        Its result folder (named in the line: where to look).

    Returns
    -------
    str or None
        ``"lost control at t = 2.03 s (...), then diverged at t = 4.28 s: ...; first: ...;
        look at ..."``; for a completed run whose status is not ok (:mod:`imdrive.run.status`)
        its causes in time order (``"R2 held since t = 4.5 s (voltage limit); R2_hat off by
        +25 %; look at ..."``); None for a run whose status is ok. A hold of R̂2 that began
        before a loss of control is named first.
    """
    lost, diverged = res.lost_control, res.diverged
    v = _verdict(res)
    if not (lost or diverged):
        if v is None or v["verdict"] == "ok":
            return None
        where = _where(out, ("estimator.png", "speed.png", "report.html"))
        t0 = v["verdict_at_s"]
        return f"{v['verdict_text']}; look at {where} around t = {t0:.3g} s"
    earlier = None
    if v is not None and v["verdict"] in ("frozen", "held"):
        earlier = v["verdict_text"].split("; ")[0]
    if lost and (not diverged or res.lost_control_at_s < res.end_time_s):
        t0 = res.lost_control_at_s
        line = res.lost_control_message
        if diverged:
            line += f"; then {res.divergence_message}"
        parts = [line]
        moved = _what_moved(res, t0)
        if moved:
            parts.append(f"first: {moved}")
        hint = tuning_hint(res)
        if hint:
            parts.append(hint)
    else:
        t0 = res.end_time_s
        parts = [res.divergence_message]
    if earlier:
        parts[0] = f"{earlier}, then {parts[0]}"
    where = _where(out, ("speed.png", "estimator.png", "report.html"))
    parts.append(f"look at {where} around t = {t0:.3g} s")
    return "; ".join(parts)
