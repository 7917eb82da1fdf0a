"""The result of a run: named signals with their unit in the name, summary, export, figures."""

from __future__ import annotations

import json
import math
import platform
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from imdrive.kernels import layout as Lo

RPM = 2.0 * math.pi / 60.0
SQ3_2 = math.sqrt(3.0) / 2.0

STATUS_TEXT = {
    Lo.S_OK: "ok",
    Lo.S_NAN: "a state became NaN or infinite",
    Lo.S_CURRENT: "stator current magnitude |i_s| exceeded simulation.divergence_current_A",
    Lo.S_SPEED: "speed |w_m| exceeded simulation.divergence_speed_rpm",
}
STATUS_SIGNAL = {Lo.S_NAN: "state", Lo.S_CURRENT: "i_s_A", Lo.S_SPEED: "speed_rpm"}

# column name -> (log index, scale): exported value = log[:, index] * scale
_DIRECT = {
    "time_s": (Lo.L_TIME, 1.0),
    "speed_rpm": (Lo.L_W_M, 1.0 / RPM),
    "w_m_rad_s": (Lo.L_W_M, 1.0),
    "torque_Nm": (Lo.L_TE, 1.0),
    "load_torque_Nm": (Lo.L_TL, 1.0),
    "i_alpha_A": (Lo.L_I_A, 1.0),
    "i_beta_A": (Lo.L_I_B, 1.0),
    "psi_r_alpha_Wb": (Lo.L_PSI_R_A, 1.0),
    "psi_r_beta_Wb": (Lo.L_PSI_R_B, 1.0),
    "v_alpha_V": (Lo.L_V_A, 1.0),
    "v_beta_V": (Lo.L_V_B, 1.0),
    "R1_ohm": (Lo.L_R1, 1.0),
    "R2_ohm": (Lo.L_R2, 1.0),
    "speed_ref_rpm": (Lo.L_W_REF, 1.0 / RPM),
    "speed_est_rpm": (Lo.L_W_HAT, 1.0 / RPM),
    "id_ref_A": (Lo.L_ID_REF, 1.0),
    "iq_ref_A": (Lo.L_IQ_REF, 1.0),
    "i_d_A": (Lo.L_I_D, 1.0),
    "i_q_A": (Lo.L_I_Q, 1.0),
    "R2_est_ohm": (Lo.L_R2_HAT, 1.0),
    "e_d0_Wb": (Lo.L_E_D0, 1.0),
    "e_q0_Wb": (Lo.L_E_Q0, 1.0),
    "flux_Wb": (Lo.L_FLUX, 1.0),
    "theta_e_rad": (Lo.L_THETA_E, 1.0),
    "theta1_C": (Lo.L_TH1, 1.0),
    "theta2_C": (Lo.L_TH2, 1.0),
    "e_d0_demod_Wb": (Lo.L_DEMOD, 1.0),
    "lam_v_alpha_Wb": (Lo.L_LAM_V_A, 1.0),
    "lam_v_beta_Wb": (Lo.L_LAM_V_B, 1.0),
    "lam_i_alpha_Wb": (Lo.L_LAM_F_A, 1.0),
    "lam_i_beta_Wb": (Lo.L_LAM_F_B, 1.0),
}
OPEN_LOOP_COLUMNS = (
    "time_s speed_rpm w_m_rad_s torque_Nm load_torque_Nm i_a_A i_b_A i_c_A i_alpha_A i_beta_A "
    "psi_r_alpha_Wb psi_r_beta_Wb v_alpha_V v_beta_V R1_ohm R2_ohm flux_Wb theta1_C theta2_C"
).split()
VECTOR_COLUMNS = (
    OPEN_LOOP_COLUMNS
    + (
        "speed_ref_rpm speed_est_rpm id_ref_A iq_ref_A i_d_A i_q_A R2_est_ohm e_d0_Wb e_q0_Wb "
        "theta_e_rad lam_v_alpha_Wb lam_v_beta_Wb lam_i_alpha_Wb lam_i_beta_Wb e_d0_demod_Wb"
    ).split()
)


def columns_from_log(log: np.ndarray, vector: bool) -> dict[str, np.ndarray]:
    """Named, unit-carrying columns from a raw kernel log (rows x N_LOG)."""
    out = {}
    names = VECTOR_COLUMNS if vector else OPEN_LOOP_COLUMNS
    for name in names:
        if name in _DIRECT:
            idx, scale = _DIRECT[name]
            out[name] = log[:, idx] * scale
    ia, ib = log[:, Lo.L_I_A], log[:, Lo.L_I_B]
    out["i_a_A"] = ia.copy()
    out["i_b_A"] = -0.5 * ia + SQ3_2 * ib
    out["i_c_A"] = -0.5 * ia - SQ3_2 * ib
    return {n: out[n] for n in names}


def package_versions() -> dict[str, str]:
    import numba
    import scipy

    import imdrive

    return {
        "imdrive": imdrive.__version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
    }


@dataclass
class SimulationResult:
    """Signals and summary of one run.

    Attributes
    ----------
    signals : dict[str, numpy.ndarray]
        Columns named with their unit (``speed_rpm``, ``torque_Nm``, ``e_d0_Wb``, ...).
    scenario : Scenario
        The scenario as run.
    diverged : bool
        Whether the run stopped early because a state left its physical bounds.
    """

    scenario: object
    signals: dict[str, np.ndarray]
    x_initial: np.ndarray
    x_final: np.ndarray
    c_final: np.ndarray
    par: np.ndarray
    status: int = Lo.S_OK
    k_end: int = 0
    wall_time_s: float = 0.0
    derived: dict = field(default_factory=dict)
    startup_s: float = 0.0  # kernel load (from the on-disk cache) or compilation

    @classmethod
    def from_log(cls, scenario, log, x0, x, c, par, status, k_end, wall, derived):
        vector = scenario.drive.mode == "vector"
        return cls(
            scenario=scenario,
            signals=columns_from_log(log, vector),
            x_initial=x0,
            x_final=x,
            c_final=c,
            par=par,
            status=status,
            k_end=k_end,
            wall_time_s=wall,
            derived=derived,
        )

    # -- access ----------------------------------------------------------------------------
    def __getitem__(self, name: str) -> np.ndarray:
        return self.signals[name]

    @property
    def columns(self) -> list[str]:
        return list(self.signals)

    @property
    def time_s(self) -> np.ndarray:
        return self.signals["time_s"]

    @property
    def diverged(self) -> bool:
        return self.status != Lo.S_OK

    @property
    def end_time_s(self) -> float:
        return self.k_end * self.scenario.simulation.Ts_s

    @property
    def divergence_message(self) -> str | None:
        if not self.diverged:
            return None
        return f"diverged at t = {self.end_time_s:.6g} s: {STATUS_TEXT[self.status]}"

    def raise_if_diverged(self) -> SimulationResult:
        """Raise :class:`~imdrive.errors.SimulationDiverged` (carrying this result) if the run
        diverged; return the result otherwise, so scripts can write
        ``res = simulate(sc).raise_if_diverged()``."""
        if self.diverged:
            from imdrive.errors import SimulationDiverged

            raise SimulationDiverged(self.end_time_s, STATUS_TEXT[self.status], self)
        return self

    def to_pandas(self):
        """The signals as a pandas DataFrame (one column per signal, unit in the name)."""
        import pandas as pd

        return pd.DataFrame(self.signals)

    def window(self, t0: float, t1: float | None = None) -> dict[str, np.ndarray]:
        """Signals restricted to ``t0 <= t <= t1``."""
        t = self.time_s
        sel = (t >= t0) & (t <= (t1 if t1 is not None else t[-1]))
        return {k: v[sel] for k, v in self.signals.items()}

    def mean(self, name: str, t0: float, t1: float | None = None) -> float:
        """Mean of a signal over a time window."""
        return float(np.mean(self.window(t0, t1)[name]))

    # -- energy ------------------------------------------------------------------------------
    def energy_balance(self) -> dict[str, float]:
        """Energies over the run, J (from the integrated accumulators of the plant)."""
        from imdrive.kernels.machine import magnetic_energy

        x = self.x_final
        x0 = self.x_initial
        J = self.scenario.machine.J_kgm2
        w_mag_end = magnetic_energy(x, self.par)
        w_mag_start = magnetic_energy(x0, self.par)
        return {
            "input_J": x[Lo.X_E_IN],
            "copper_loss_J": x[Lo.X_E_CU],
            "airgap_work_J": x[Lo.X_E_EM],
            "load_and_friction_work_J": x[Lo.X_E_LOAD],
            "magnetic_energy_change_J": w_mag_end - w_mag_start,
            "kinetic_energy_change_J": 0.5 * J * (x[Lo.X_W_M] ** 2 - x0[Lo.X_W_M] ** 2),
        }

    def compensation_metrics(self, tol: float = 0.02, window_s: float = 0.5) -> dict | None:
        """How the R2 compensator did (None when it is off).

        ``time_to_tol_s``: time from the compensator's enable instant after which
        ``|R2_hat/R2 - 1| <= tol`` holds to the end of the run (None if it never settles
        there). Speed errors (actual minus reference, rpm) are means over ``window_s`` just
        before the enable instant and at the end of the run; the ripple is the peak-to-peak
        actual speed over the final window.
        """
        comp = self.scenario.compensator
        if not comp.enabled or self.scenario.drive.mode != "vector" or len(self.time_s) < 2:
            return None
        s = self.signals
        t = s["time_s"]
        t_on = comp.t_on_s
        ratio_err = np.abs(s["R2_est_ohm"] / s["R2_ohm"] - 1.0)
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
        return {
            "R2_ohm": float(s["R2_ohm"][-1]),
            "R2_est_initial_ohm": float(s["R2_est_ohm"][0]),
            "R2_est_final_ohm": float(s["R2_est_ohm"][-1]),
            "R2_est_final_error_pct": float(100.0 * (s["R2_est_ohm"][-1] / s["R2_ohm"][-1] - 1)),
            "tolerance_pct": 100.0 * tol,
            "time_to_tolerance_s": t_tol,
            "speed_error_before_rpm": float(np.mean(err[before])) if before.any() else None,
            "speed_error_after_rpm": float(np.mean(err[after])),
            "speed_ripple_after_rpm": float(np.ptp(s["speed_rpm"][after])),
            "e_d0_mean_after_Wb": float(np.mean(s["e_d0_Wb"][after])),
        }

    # -- summary and export ------------------------------------------------------------------
    def final_values(self) -> dict[str, float]:
        return {k: float(v[-1]) for k, v in self.signals.items() if len(v)}

    def summary(self) -> dict:
        """What ``summary.json`` holds: scenario as run, versions, final values, wall time."""
        return {
            "scenario": self.scenario.to_dict(),
            "derived": {k: float(v) for k, v in self.derived.items()},
            "versions": package_versions(),
            "status": STATUS_TEXT[self.status],
            "diverged": self.diverged,
            "diverged_at_s": self.end_time_s if self.diverged else None,
            "diverged_signal": STATUS_SIGNAL.get(self.status),
            "simulated_time_s": self.end_time_s,
            "control_periods": self.k_end,
            "wall_time_s": self.wall_time_s,
            "kernel_startup_s": self.startup_s,
            "real_time_factor": (self.end_time_s / self.wall_time_s) if self.wall_time_s else None,
            "final": self.final_values(),
            "energy_J": {k: float(v) for k, v in self.energy_balance().items()},
            "compensation": self.compensation_metrics(),
        }

    def to_csv(self, path) -> None:
        """Write the signals as CSV (header = column names with units)."""
        names = self.columns
        data = np.column_stack([self.signals[n] for n in names])
        np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")

    def save(self, out_dir, figures: bool | None = None, csv: bool | None = None) -> list[Path]:
        """Write ``timeseries.csv``, ``summary.json`` and PNG figures into ``out_dir``.

        Files are first written to a temporary folder inside ``out_dir`` and moved in place at
        the end, ``summary.json`` last (an older ``summary.json`` is removed first), so an
        interrupted write never looks complete (:class:`imdrive._io.AtomicFolder`).
        """
        from imdrive._io import AtomicFolder

        figures = self.scenario.output.figures if figures is None else figures
        csv = self.scenario.output.csv if csv is None else csv
        with AtomicFolder(out_dir, marker="summary.json") as staging:
            if csv:
                self.to_csv(staging.path / "timeseries.csv")
            if figures:
                from imdrive.plots import save_figures

                save_figures(self, staging.path)
            (staging.path / "summary.json").write_text(json.dumps(self.summary(), indent=2) + "\n")
        return staging.written
