"""The drive at a stationary operating point, for the linear analysis of :mod:`imdrive.stability`.

What the stability maps need of a drive, in one place of the run layer: the scenario's records
with every profile at a constant value and one row per grid point
(:func:`stationary_drive`), the constants of the plant and the controller's model
(:func:`model_coefficients`), and the compiled one-period map in the controller's frame with
its reduced state (:mod:`imdrive.kernels.linearise`, re-exported here: ``N_Z``, ``N_U``,
``Z_SCALE``, ``solve_points``, ``propagate``, ``step_check``, the point status codes) and the
profile slots.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from imdrive.config.commissioning_ideal import current_gain_b_per_a
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.kernels.engine import DriveParams, DriveState
from imdrive.kernels.estimators.registry import kernel, kernel_names
from imdrive.kernels.linearise import (
    N_D,
    N_U,
    N_Z,
    P_DIVERGED,
    P_NO_CONVERGENCE,
    P_OK,
    Z_SCALE,
    pack_state,
    propagate,
    reduced_state_of,
    solve_points,
    state_scale,
    step_check,
)
from imdrive.kernels.profiles import (
    N_PROF,
    PR_FLUX_REF,
    PR_LOAD,
    PR_R1_SCALE,
    PR_R2_SCALE,
    PR_SPEED_REF,
)
from imdrive.run.build import build_arrays
from imdrive.run.estimators import estimator_of

__all__ = [
    "N_D",
    "N_PROF",
    "N_U",
    "N_Z",
    "PR_FLUX_REF",
    "PR_LOAD",
    "PR_R1_SCALE",
    "PR_R2_SCALE",
    "PR_SPEED_REF",
    "P_DIVERGED",
    "P_NO_CONVERGENCE",
    "P_OK",
    "Z_SCALE",
    "DriveParams",
    "DriveState",
    "StationaryDrive",
    "model_coefficients",
    "pack_state",
    "propagate",
    "reduced_estimators",
    "reduced_state_of",
    "solve_points",
    "state_scale",
    "stationary_drive",
    "step_check",
]


@dataclass
class StationaryDrive:
    """One drive's records with constant profiles, replicated to ``n`` rows."""

    P: DriveParams
    S: DriveState
    TH: np.ndarray  # (n, 2) frozen winding temperatures, degC
    Ts: float
    v_max: float
    i_max: float


def stationary_drive(sc: Scenario, speeds_rad_s, torques_Nm) -> StationaryDrive:
    """Records of ``sc`` with every profile at its final value, references set per row."""
    if sc.drive.mode != "vector":
        raise ConfigError("drive.mode", "stability maps need the vector (IFOC) drive")
    if not estimator_of(sc).kernel.reduced_state:
        # an estimator whose states the reduced state (imdrive.kernels.linearise) does not
        # carry would be missing from the map (a NaN Jacobian, not a result)
        mapped = ", ".join(f'"{k}"' for k in reduced_estimators())
        raise ConfigError(
            "control.speed_feedback",
            f'stability maps cover {mapped} and "measured": "{sc.control.speed_feedback}" '
            "gives the map no reduced state (its states are not in the linearised loop)",
        )
    if sc.plant.speed_mode == "imposed":
        raise ConfigError("plant.speed_mode", "stability maps need the mechanical model")
    if sc.sensor.i_offset_alpha_A != 0.0 or sc.sensor.i_offset_beta_A != 0.0:
        raise ConfigError(
            "sensor", "a current-sensor offset breaks rotation invariance (no fixed point)"
        )
    # the reduced state covers the average-value drive; per-phase effects are not rotation
    # invariant (no fixed point in the controller's frame), and the delay's held voltage is
    # not part of the state yet
    if sc.inverter.model != "average":
        raise ConfigError("inverter.model", 'stability maps need the "average" inverter model')
    if sc.inverter.dead_time_s > 0.0 or sc.inverter.device_drop_V > 0.0:
        raise ConfigError(
            "inverter.dead_time_s",
            "dead time and device drops act per phase: no fixed point (set both to 0)",
        )
    if sc.sensor.per_phase or sc.sensor.vdc_gain != 1.0 or current_gain_b_per_a(sc) != 1.0:
        raise ConfigError(
            "sensor", "per-phase sensor errors break rotation invariance (no fixed point)"
        )
    if sc.control.delay_periods != 0:
        raise ConfigError(
            "control.delay_periods", "stability maps model the drive without computation delay"
        )
    one = replace(sc.simulation, t_end_s=sc.simulation.Ts_s, tracking_windows=None)
    a = build_arrays(replace(sc, simulation=one))
    n = len(speeds_rad_s)
    rep = lambda arr: np.repeat(arr, n, axis=0)  # noqa: E731
    pv = a.params.prof_v[0]
    pn = a.params.prof_n[0]
    final = np.array([pv[s, pn[s] - 1] for s in range(N_PROF)])
    prof_t = np.zeros((n, N_PROF, 1))
    prof_v = np.repeat(final[None, :, None], n, axis=0)
    prof_v[:, PR_SPEED_REF, 0] = speeds_rad_s
    prof_v[:, PR_LOAD, 0] = torques_Nm
    # every block's record replicated (whatever the blocks are), then the profiles replaced
    P = DriveParams(*(f if name == "tables" else rep(f) for name, f in a.params._asdict().items()))
    P = P._replace(
        prof_t=prof_t,
        prof_v=prof_v,
        prof_n=np.ones((n, N_PROF), dtype=np.int64),
        table_idx=np.zeros(n, dtype=np.int64),
    )
    for k in _RESISTANCE_RATES:
        # the map holds the resistance estimates, as it holds the compensator's: an online
        # R1 or R2 law would move them between the map's evaluations, outside its state
        if k in P.est.dtype.names:
            P.est[k] = 0.0
    S = DriveState(*(rep(f) for f in a.state0))
    TH = np.repeat(np.array([[S.plant["theta1"][0], S.plant["theta2"][0]]]), n, axis=0)
    return StationaryDrive(
        P=P,
        S=S,
        TH=TH,
        Ts=a.Ts,
        v_max=float(a.params.control["v_max"][0]),
        i_max=float(a.params.control["i_max"][0]),
    )


#: The estimators' parameter fields of an online resistance law (MRAS: R1; observer: R1, R2).
_RESISTANCE_RATES = ("k_R1", "k_R2")


def reduced_estimators() -> tuple[str, ...]:
    """Names of the registered estimators the stability maps linearise."""
    return tuple(n for n in kernel_names() if kernel(n).reduced_state)


def model_coefficients(P: DriveParams, S: DriveState) -> dict:
    """Plant, model and controller constants of row 0 (SI)."""
    pp = P.plant[0]
    md = S.model[0]
    c = {k: float(pp[k]) for k in ("R1", "R2", "Ll1", "Ll2", "M", "n_p", "J", "B", "k_visc")}
    c["k_fan"] = float(pp["k_fan"])
    pv = P.prof_v[0]
    c["R1"] *= pv[PR_R1_SCALE, 0]
    c["R2"] *= pv[PR_R2_SCALE, 0]
    c["L1"] = c["Ll1"] + c["M"]
    c["L2"] = c["Ll2"] + c["M"]
    for k in ("R1_hat", "R2_hat", "Ll1_hat", "Ll2_hat", "M_hat"):
        c[k] = float(md[k])
    c["L1_hat"] = c["Ll1_hat"] + c["M_hat"]
    c["L2_hat"] = c["Ll2_hat"] + c["M_hat"]
    c["sL1_hat"] = c["L1_hat"] - c["M_hat"] ** 2 / c["L2_hat"]
    c["psi_ref"] = float(pv[PR_FLUX_REF, 0])
    c["sensorless"] = bool(P.sim[0]["sensorless"])
    for k in ("wc", "wc_k", "wc_min", "K2", "b2", "b2_wmin"):  # an MRAS drive's (as before)
        if k in P.est.dtype.names:
            c[k] = float(P.est[0][k])
    c["decouple"] = bool(P.control[0]["decouple"])
    return c
