"""Stability maps over speed x load torque, and their check against simulation.

:func:`stability_map` solves the steady state and the discrete small-signal model
(:mod:`imdrive.stability.linear`) at every point of a speed x torque grid and tabulates the
least stable mode. :func:`validate_map` simulates the nonlinear loop from each fixed point after
a small speed-reference step and compares the verdicts (confusion table).
"""

from __future__ import annotations

import math

import numpy as np

from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError, check_argument
from imdrive.run import linear as rl
from imdrive.stability.linear import (
    RPM,
    STATUS_OK,
    _rows,
    map_scenario,
    solve_operating_points,
)

__all__ = ["MAP_COLUMNS", "stability_map", "validate_map", "boundary_neighbours"]

#: columns of :func:`stability_map`'s table
MAP_COLUMNS = (
    "speed_rpm",
    "torque_Nm",
    "status",
    "stable",
    "max_real_1_per_s",
    "damping",
    "frequency_Hz",
    "max_abs_z",
    "speed_actual_rpm",
    "speed_est_rpm",
    "R1_ratio",
    "R2_ratio",
    "M_ratio",
    "flux_factor",
)


def _check_axis(values, name: str) -> np.ndarray:
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)):
        raise ConfigError(name, "must be a non-empty 1-D list of finite numbers")
    return arr


def dominant_modes(ev: np.ndarray, Ts: float):
    """Least stable mode of each row of z-plane eigenvalues ``ev`` (N, n).

    Returns ``(max_real, damping, frequency_Hz, max_abs_z)``: the largest real part of
    ``s = ln(z)/Ts`` (1/s), that mode's damping ``-Re s/|s|`` and frequency ``|Im s|/2 pi`` (Hz),
    and the spectral radius. Zero eigenvalues (pure delays) are skipped; NaN rows stay NaN.
    """
    mag = np.abs(ev)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.log(np.where(mag > 1e-12, ev, np.nan)) / Ts
    re = np.where(np.isnan(s.real), -np.inf, s.real)
    k = np.argmax(re, axis=1)
    dom = s[np.arange(len(s)), k]
    allnan = np.all(np.isnan(ev), axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        damping = np.where(np.abs(dom) > 0, -dom.real / np.abs(dom), 1.0)
    out = (dom.real, damping, np.abs(dom.imag) / (2 * math.pi), np.max(mag, axis=1))
    return tuple(np.where(allnan, np.nan, o) for o in out)


def stability_map(
    scenario: Scenario,
    speeds_rpm,
    torques_Nm,
    *,
    R1_ratio: float | None = None,
    R2_ratio: float | None = None,
    M_ratio: float | None = None,
):
    """Small-signal stability of the drive over a speed x load-torque grid.

    Parameters
    ----------
    scenario : Scenario
        The drive (machine, gains, filters, estimates, control period). Its compensator is
        frozen (R2_hat stays at the scenario's initial estimate); its profiles are replaced by
        constant references.
    speeds_rpm, torques_Nm : array_like
        Grid axes: speed references (mechanical rpm) and load torques (N m, positive =
        motoring at positive speed, negative = regenerating).
    R1_ratio, R2_ratio, M_ratio : float, optional
        Controller's estimates as multiples of the plant's ``R1``, ``R2``, ``M``
        (:func:`imdrive.stability.linear.map_scenario`); default: the scenario's ``[estimator]``.

    Returns
    -------
    pandas.DataFrame
        One row per grid point, speeds outer, columns :data:`MAP_COLUMNS`: ``status`` (``ok``,
        ``current_limit``, ``voltage_limit``, ``no_steady_state``, ``diverged``), ``stable``
        (all eigenvalues of the discrete loop inside the unit circle; False where status is not
        ok), ``max_real_1_per_s`` (largest real part of ``ln(z)/Ts``), the dominant mode's
        ``damping`` and ``frequency_Hz``, the spectral radius ``max_abs_z``, the steady-state
        true speed and speed estimate (rpm), the parameter ratios, and ``flux_factor``: the
        flux the point is linearised at over the reference, below 1 where the drive's field
        weakening lowers it (:func:`_field_weakened`).
    """
    import pandas as pd

    from imdrive.config.defaults import in_effect

    check_argument(scenario, Scenario, "scenario", "a Scenario (Scenario.read(...))")
    sp = _check_axis(speeds_rpm, "speeds_rpm")
    tq = _check_axis(torques_Nm, "torques_Nm")
    sc = map_scenario(scenario, R1_ratio=R1_ratio, R2_ratio=R2_ratio, M_ratio=M_ratio)
    S, T = np.meshgrid(sp, tq, indexing="ij")
    # with field weakening its loop is held (at the reference flux here; where the drive
    # lowers the flux, at that flux: _field_weakened): it is not a state of the reduced map
    fw = 1.0 if in_effect(scenario, "control.field_weakening") else None
    ops = solve_operating_points(sc, S.ravel(), T.ravel(), flux_factor=fw)
    max_real, damping, freq, rho = dominant_modes(ops.eigenvalues(), ops.Ts)
    ok = ops.status == STATUS_OK
    c = ops.coeffs
    m = scenario.machine
    df = pd.DataFrame(
        {
            "speed_rpm": S.ravel(),
            "torque_Nm": T.ravel(),
            "status": ops.status.astype(str),
            "stable": ok & (rho < 1.0),
            "max_real_1_per_s": max_real,
            "damping": damping,
            "frequency_Hz": freq,
            "max_abs_z": rho,
            "speed_actual_rpm": ops.z[:, 4] / RPM,
            "speed_est_rpm": ops.z[:, 20] / (c["n_p"] * RPM),
            "R1_ratio": c["R1_hat"] / (m.R1_ohm * scenario.plant.R1_scale.final),
            "R2_ratio": c["R2_hat"] / (m.R2_ohm * scenario.plant.R2_scale.final),
            "M_ratio": c["M_hat"] / m.M_H,
        }
    )
    df["flux_factor"] = 1.0
    _field_weakened(scenario, sc, df, ops)
    df.attrs["Ts_s"] = ops.Ts
    df.attrs["note"] = field_weakening_note(scenario, df)
    return df


#: the field weakening's steady flux factor (:func:`steady_flux_factor`): scanned down from 1
#: in these steps, then bisected 2^-20 of a step
_FW_SCAN = 0.02
_FW_BISECTIONS = 20


def steady_flux_factor(c: dict, v_max: float, fw: dict, w_ref: float, T_L: float) -> float:
    """The flux factor ``k`` the field weakening holds in steady state at one point
    (kernels/ifoc.py ``field_weakening``): the voltage feedback's, where the continuous steady
    state's voltage ``|R1 i + j w_e psi_s|`` at the flux ``k psi*`` is ``fw_v`` of the limit
    ``v_max`` (bisection; the voltage rises with ``k``), capped by the no-load bound
    ``fw_v v_max M/(|w_e| L1 psi*)`` where ``fw_bound``, and at least ``fw_min``; 1 where the
    reference flux needs no more than ``fw_v``. ``fw``: ``fw_v``, ``fw_min``, ``fw_bound``
    of the control record."""
    from imdrive.stability.steady import _plant_in_frame, continuous_steady_state

    def at(k: float) -> tuple[float, float]:
        ck = dict(c, psi_ref=k * c["psi_ref"])
        iq, w_m, ok = continuous_steady_state(ck, np.array([w_ref]), np.array([T_L]))
        I, psi_s, _, w_e, _ = _plant_in_frame(ck, iq, w_m, np.array([w_ref]))
        v = abs(c["R1"] * I[0] + 1j * w_e[0] * psi_s[0]) if ok[0] else math.inf
        return v / v_max, float(w_e[0])

    # the largest k whose voltage is within fw_v: the voltage falls with k from the reference
    # flux down to where the torque current it needs takes over, so scan down, then bisect
    hi = lo = 1.0
    while lo > fw["fw_min"] and at(lo)[0] > fw["fw_v"]:
        hi, lo = lo, max(lo - _FW_SCAN, fw["fw_min"])
    if at(lo)[0] > fw["fw_v"]:
        return fw["fw_min"]  # not even the lowest flux holds it: the point stays limited
    if lo < hi:
        for _ in range(_FW_BISECTIONS):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if at(mid)[0] <= fw["fw_v"] else (lo, mid)
    k = lo
    if fw["fw_bound"]:
        w_e = at(k)[1]
        if w_e != 0.0:
            k = min(k, fw["fw_v"] * v_max * c["M_hat"] / (abs(w_e) * c["L1_hat"] * c["psi_ref"]))
    return max(k, fw["fw_min"])


def _field_weakened(scenario: Scenario, sc: Scenario, df, ops) -> None:
    """Solve again, at the flux the field weakening holds, the points of a drive with
    ``control.field_weakening`` whose reference flux needs more than ``fw_v`` of the
    inverter's voltage (in place: ``df``'s rows and its ``flux_factor`` column).

    The drive reaches them in simulation with a lowered flux; the map linearises it there with
    the field weakening's integrator frozen at its steady flux factor (quasi-static: the loop
    holds the voltage over many rotor time constants and is not a state of the reduced map).
    Measured at the rated point of every library machine, motoring and regenerating
    (tests/stability/test_field_weakening_map.py): the map's flux factor within 1 % of the
    simulated drive's flux ratio, and stable where the simulated drive holds."""
    from imdrive.config.defaults import in_effect

    if not in_effect(scenario, "control.field_weakening"):
        return
    rec = ops.drive.P.control[0]
    fw = {name: rec[name] for name in ("fw_v", "fw_min", "fw_bound")}
    c = ops.coeffs
    for i in np.flatnonzero(
        df["status"].isin(["ok", "voltage_limit", "no_steady_state"]).to_numpy()
    ):
        s_rpm, t_nm = float(df.at[i, "speed_rpm"]), float(df.at[i, "torque_Nm"])
        k = steady_flux_factor(c, ops.drive.v_max, fw, s_rpm * RPM, t_nm)
        if k >= 1.0:
            continue
        one = solve_operating_points(sc, [s_rpm], [t_nm], flux_factor=k)
        max_real, damping, freq, rho = dominant_modes(one.eigenvalues(), one.Ts)
        ok = one.status[0] == STATUS_OK
        df.loc[i, ["status", "stable", "flux_factor"]] = [one.status[0], ok and rho[0] < 1.0, k]
        df.loc[i, ["max_real_1_per_s", "damping", "frequency_Hz", "max_abs_z"]] = [
            max_real[0],
            damping[0],
            freq[0],
            rho[0],
        ]
        df.loc[i, "speed_actual_rpm"] = one.z[0, 4] / RPM
        df.loc[i, "speed_est_rpm"] = one.z[0, 20] / (c["n_p"] * RPM)


def field_weakening_note(scenario: Scenario, df) -> str | None:
    """What the map did with the field weakening of a drive that has it
    (``control.field_weakening``, on by default where the speed reaches the inverter's voltage
    at rated torque): the points it linearised at a lowered flux (``flux_factor`` below 1,
    :func:`_field_weakened`) and those that need more voltage than the lowest flux factor
    gives (``voltage_limit``). None where the drive has no field weakening or the map no such
    point."""
    from imdrive.config.defaults import in_effect

    if not in_effect(scenario, "control.field_weakening"):
        return None
    n_fw = int((df["flux_factor"] < 1.0).sum())
    n_v = int((df["status"] == "voltage_limit").sum())
    parts = []
    if n_fw:
        parts.append(
            f"{n_fw} point(s) linearised at the lowered flux the field weakening holds there "
            "(flux_factor; its slow loop frozen at that factor)"
        )
    if n_v:
        parts.append(
            f"{n_v} point(s) need more than the inverter's voltage even at "
            "control.field_weakening_min (voltage_limit)"
        )
    return "; ".join(parts) or None


def boundary_neighbours(stable: np.ndarray) -> np.ndarray:
    """Cells of a 2-D boolean grid with a 4-neighbour of the other verdict (the boundary)."""
    g = np.asarray(stable, dtype=bool)
    near = np.zeros_like(g)
    near[1:, :] |= g[1:, :] != g[:-1, :]
    near[:-1, :] |= g[:-1, :] != g[1:, :]
    near[:, 1:] |= g[:, 1:] != g[:, :-1]
    near[:, :-1] |= g[:, :-1] != g[:, 1:]
    return near


def simulate_steps(
    scenario: Scenario, speeds_rpm, torques_Nm, *, step_rpm=0.5, horizon_s=2.0, seed=0
):
    """Nonlinear verdicts: each point simulated from its steady state after a speed step.

    Each drive starts at its fixed point plus a random perturbation of 1e-6 of every state's
    scale (so that every mode is excited, also those the speed step does not reach), its speed
    reference steps by ``step_rpm``, and the engine runs ``horizon_s``. The distance of the
    state to the fixed point of the stepped reference is kept per 50 ms window
    (:func:`imdrive.kernels.linearise.step_check`). Verdict *stable* when the drive does not
    diverge, the distance in the last window is below that in the first (no growth beyond
    the excitation: no runaway, no limit cycle larger than the step) and the log of the window
    peaks over the second half of the horizon falls (fitted growth rate < 0).

    Returns
    -------
    sim_stable : ndarray of bool
        False also where the point has no steady state.
    growth_1_per_s : ndarray
        Fitted growth rate of the window peaks over the second half, 1/s (inf: diverged).
    ops : OperatingPoints
    """
    sc = map_scenario(scenario)
    speeds = np.asarray(speeds_rpm, dtype=float)
    torques = np.asarray(torques_Nm, dtype=float)
    ops = solve_operating_points(sc, speeds, torques)
    stepped = solve_operating_points(sc, speeds + step_rpm, torques)
    n = len(ops.status)
    ok = ops.status == STATUS_OK
    sim_stable = np.zeros(n, dtype=bool)
    growth = np.full(n, np.nan)
    idx = np.flatnonzero(ok)
    if not len(idx):
        return sim_stable, growth, ops
    P, S, TH = _rows(ops.drive, idx)  # copies: the stepped reference is written into P
    P.prof_v[:, rl.PR_SPEED_REF, 0] += step_rpm * RPM
    z_old = ops.z[idx]
    rng = np.random.default_rng(seed)
    Z0 = z_old + 1e-6 * rng.standard_normal(z_old.shape) * (np.abs(z_old) + rl.state_scale(S))
    Z1 = np.where((stepped.status[idx] == STATUS_OK)[:, None], stepped.z[idx], z_old)
    n_win = max(int(round(0.05 / ops.Ts)), 1)
    n_steps = int(round(horizon_s / ops.Ts))
    n_w = n_steps // n_win
    peaks = np.empty((len(idx), n_w))
    status = np.empty(len(idx), dtype=np.int64)
    rl.step_check(
        P,
        S,
        np.ascontiguousarray(Z0),
        np.ascontiguousarray(Z1),
        TH,
        n_steps,
        n_win,
        peaks,
        status,
    )
    half = n_w // 2
    t = (np.arange(half, n_w) + 0.5) * n_win * ops.Ts
    with np.errstate(divide="ignore", invalid="ignore"):
        logp = np.log(peaks[:, half:])
    for r, i in enumerate(idx):
        if status[r] != 0 or not np.all(np.isfinite(logp[r])):
            growth[i] = np.inf
            continue
        growth[i] = np.polyfit(t, logp[r], 1)[0]
        sim_stable[i] = growth[i] < 0.0 and peaks[r, -1] < peaks[r, 0]
    return sim_stable, growth, ops


def validate_map(
    scenario: Scenario,
    speeds_rpm,
    torques_Nm,
    R1_ratios=(1.0,),
    *,
    step_rpm: float = 0.5,
    horizon_s: float = 2.0,
):
    """Compare the map's verdicts with simulation on a speed x torque x R1_hat/R1 grid.

    Parameters
    ----------
    scenario : Scenario
        The sensorless drive.
    speeds_rpm : array_like
        Speed references of the grid, rpm.
    torques_Nm : array_like
        Load torques of the grid, N m.
    R1_ratios : sequence of float
        ``R1_hat/R1`` values, dimensionless: one map each.
    step_rpm : float
        Speed-reference step applied at each fixed point, rpm.
    horizon_s : float
        Simulated time after the step, s.

    Returns
    -------
    table : pandas.DataFrame
        One row per point: the map columns plus ``sim_stable``, ``sim_growth_1_per_s`` and
        ``near_boundary`` (a 4-neighbour in speed x torque has the other map verdict).
    confusion : pandas.DataFrame
        Counts of map verdict (rows) against simulation verdict (columns) over the points
        with a steady state.
    """
    import pandas as pd

    sp = _check_axis(speeds_rpm, "speeds_rpm")
    tq = _check_axis(torques_Nm, "torques_Nm")
    frames = []
    for r in R1_ratios:
        sc = map_scenario(scenario, R1_ratio=r)
        df = stability_map(sc, sp, tq)
        sim, growth, _ = simulate_steps(
            sc, df["speed_rpm"].to_numpy(), df["torque_Nm"].to_numpy(),
            step_rpm=step_rpm, horizon_s=horizon_s,
        )  # fmt: skip
        df["sim_stable"] = sim
        df["sim_growth_1_per_s"] = growth
        df["near_boundary"] = boundary_neighbours(
            df["stable"].to_numpy().reshape(len(sp), len(tq))
        ).ravel()
        frames.append(df)
    table = pd.concat(frames, ignore_index=True)
    have = table["status"] == STATUS_OK
    confusion = pd.crosstab(
        table.loc[have, "stable"].map({True: "map stable", False: "map unstable"}),
        table.loc[have, "sim_stable"].map({True: "sim stable", False: "sim unstable"}),
    )
    return table, confusion
