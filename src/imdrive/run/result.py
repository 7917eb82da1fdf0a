"""The result of a run: named signals with their unit in the name, summary, export, figures."""

from __future__ import annotations

import json
import math
import platform
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from imdrive.kernels.engine import S_CURRENT, S_NAN, S_OK, S_SPEED, DriveParams, DriveState
from imdrive.kernels.machine import magnetic_energy
from imdrive.kernels.records import record_bytes
from imdrive.run.metrics import (
    CONVERGENCE_BAND,
    DEFAULT_WINDOW_S,
    compensation_metrics,
    drive_metrics,
    lost_control_check,
    lost_control_time,
)

RPM = 2.0 * math.pi / 60.0
SQ3_2 = math.sqrt(3.0) / 2.0

STATUS_TEXT = {
    S_OK: "ok",
    S_NAN: "a state became NaN or infinite",
    S_CURRENT: "stator current magnitude |i_s| exceeded simulation.divergence_current_A",
    S_SPEED: "speed |w_m| exceeded simulation.divergence_speed_rpm",
}
STATUS_SIGNAL = {S_NAN: "state", S_CURRENT: "i_s_A", S_SPEED: "speed_rpm"}

#: The units table: log field (SI, see each block's LOG_FIELDS) -> (unit, scale). The exported
#: column is ``f"{field}_{unit}"`` holding ``log[field] * scale``. ``v_alpha_V``/``v_beta_V``
#: are the period-average voltage applied at the terminals over [t_k, t_k + Ts) (the bridge's
#: true average with the switching model, dead time included; the commanded one at the last
#: sample, which has no period after it); ``v_ref_*`` the controller's reference at sample k;
#: ``i_*_meas_A`` what the current sensors report, ``i_alpha_A``/``i_beta_A`` the true current.
LOG_UNITS = {
    "time": ("s", 1.0),
    "speed": ("rpm", 1.0 / RPM),
    "torque": ("Nm", 1.0),
    "load_torque": ("Nm", 1.0),
    "i_alpha": ("A", 1.0),
    "i_beta": ("A", 1.0),
    "psi_r_alpha": ("Wb", 1.0),
    "psi_r_beta": ("Wb", 1.0),
    "R1": ("ohm", 1.0),
    "R2": ("ohm", 1.0),
    "flux": ("Wb", 1.0),
    "theta1": ("C", 1.0),
    "theta2": ("C", 1.0),
    "v_alpha": ("V", 1.0),
    "v_beta": ("V", 1.0),
    "v_ref_alpha": ("V", 1.0),
    "v_ref_beta": ("V", 1.0),
    "i_alpha_meas": ("A", 1.0),
    "i_beta_meas": ("A", 1.0),
    "speed_ref": ("rpm", 1.0 / RPM),
    "id_ref": ("A", 1.0),
    "iq_ref": ("A", 1.0),
    "i_d": ("A", 1.0),
    "i_q": ("A", 1.0),
    "theta_e": ("rad", 1.0),
    "speed_est": ("rpm", 1.0 / RPM),
    "e_d0": ("Wb", 1.0),
    "e_q0": ("Wb", 1.0),
    "lam_v_alpha": ("Wb", 1.0),
    "lam_v_beta": ("Wb", 1.0),
    "lam_i_alpha": ("Wb", 1.0),
    "lam_i_beta": ("Wb", 1.0),
    "R2_est": ("ohm", 1.0),
    "R1_est": ("ohm", 1.0),
    "e_d0_demod": ("Wb", 1.0),
    "comp_frozen": ("flags", 1.0),
    "inj_freq": ("Hz", 1.0),
}
# column -> (log field, scale) for every column taken straight from the log
_DIRECT = {f"{f}_{u}": (f, k) for f, (u, k) in LOG_UNITS.items()}
_DIRECT["w_m_rad_s"] = ("speed", 1.0)  # the speed in SI as well

OPEN_LOOP_COLUMNS = (
    "time_s speed_rpm w_m_rad_s torque_Nm load_torque_Nm i_a_A i_b_A i_c_A i_alpha_A i_beta_A "
    "i_alpha_meas_A i_beta_meas_A psi_r_alpha_Wb psi_r_beta_Wb v_alpha_V v_beta_V "
    "v_ref_alpha_V v_ref_beta_V R1_ohm R2_ohm flux_Wb theta1_C theta2_C"
).split()
VECTOR_COLUMNS = (
    OPEN_LOOP_COLUMNS
    + (
        "speed_ref_rpm speed_est_rpm id_ref_A iq_ref_A i_d_A i_q_A R2_est_ohm e_d0_Wb e_q0_Wb "
        "theta_e_rad lam_v_alpha_Wb lam_v_beta_Wb lam_i_alpha_Wb lam_i_beta_Wb e_d0_demod_Wb "
        "comp_frozen_flags inj_freq_Hz R1_est_ohm"
    ).split()
)


def columns_from_log(
    log: np.ndarray, vector: bool, extra_units: dict | None = None
) -> dict[str, np.ndarray]:
    """Named, unit-carrying columns from a kernel log (a record array of the drive's log dtype).

    Parameters
    ----------
    log : numpy.ndarray
        The log records, SI units.
    vector : bool
        Field-oriented drive (the controller's columns too) or open loop.
    extra_units : dict, optional
        ``{field: (unit, scale)}`` of the estimator's own log fields
        (:class:`imdrive.run.estimators.Estimator` ``log_units``); a standard column whose field
        the log lacks (another estimator's) is left out.

    Returns
    -------
    dict
        ``{column: values}``, the standard columns in their order, then the estimator's own.
    """
    out = {}
    fields = set(log.dtype.names)
    names = list(VECTOR_COLUMNS if vector else OPEN_LOOP_COLUMNS)
    if vector:
        for field, (unit, scale) in (extra_units or {}).items():
            name = f"{field}_{unit}"
            if name not in names:
                names.insert(names.index("e_d0_demod_Wb"), name)
            if field in fields:
                out[name] = log[field] * scale
    for name in names:
        if name in _DIRECT and name not in out:
            field, scale = _DIRECT[name]
            if field in fields:
                out[name] = log[field] * scale
    ia, ib = log["i_alpha"], log["i_beta"]
    out["i_a_A"] = ia.copy()
    out["i_b_A"] = -0.5 * ia + SQ3_2 * ib
    out["i_c_A"] = -0.5 * ia - SQ3_2 * ib
    return {n: out[n] for n in names if n in out}


def _estimator_units(scenario) -> dict:
    """Units of the scenario's estimator's own log fields."""
    from imdrive.run.estimators import estimator_of

    return dict(estimator_of(scenario).log_units)


def package_versions() -> dict[str, str]:
    from importlib.metadata import version

    import imdrive

    return {
        "imdrive": imdrive.__version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": version("scipy"),
        "numba": version("numba"),
    }


@dataclass
class SimulationResult:
    """Signals and summary of one run.

    Attributes
    ----------
    signals : dict[str, numpy.ndarray]
        Columns, each in the unit its name ends with (``time_s`` in s, ``speed_rpm`` in rpm,
        ``torque_Nm`` in N m, ``e_d0_Wb`` in Wb, ...; ``docs/outputs.md``).
    scenario : Scenario
        The scenario as run.
    state_initial, state_final : DriveState
        The kernels' state records at the start and at the end of the run.
    params : DriveParams
        The kernels' parameter records.
    status : int
        0 for a completed run, else the code of what diverged (``STATUS_TEXT``).
    k_end : int
        Control periods simulated.
    wall_time_s : float
        Wall time of the kernel call, s.
    derived : dict
        Derived quantities (gains, rated values) recorded in ``summary.json``, SI units.
    startup_s : float
        Kernel load from the on-disk cache, or compilation, s.
    end_values : dict or None
        The signals at t_end when the last logged row is earlier; None: the last logged row
        is the final state.
    diverged : bool
        Whether the run stopped early because a state left its physical bounds.
    """

    scenario: object
    signals: dict[str, np.ndarray]
    state_initial: DriveState
    state_final: DriveState
    params: DriveParams
    status: int = S_OK
    k_end: int = 0
    wall_time_s: float = 0.0
    derived: dict = field(default_factory=dict)
    startup_s: float = 0.0  # kernel load (from the on-disk cache) or compilation
    #: the signals at t_end when the last logged row is earlier (log_every does not divide the
    #: number of periods); None: the last logged row is the final state
    end_values: dict | None = None

    @classmethod
    def from_log(cls, scenario, log, state0, state, params, status, k_end, wall, derived):
        """Build a result from the kernel's outputs.

        Parameters
        ----------
        scenario : Scenario
            The scenario as run.
        log : numpy.ndarray
            The log records (dtype ``LOG``), SI units.
        state0, state : DriveState
            The state records at the start and at the end.
        params : DriveParams
            The parameter records.
        status : int
            The kernel's status code (0: completed).
        k_end : int
            Control periods simulated.
        wall : float
            Wall time of the kernel call, s.
        derived : dict
            Derived quantities for the summary, SI units.

        Returns
        -------
        SimulationResult
            Signals converted to the exported units.
        """
        vector = scenario.drive.mode == "vector"
        return cls(
            scenario=scenario,
            signals=columns_from_log(log, vector, _estimator_units(scenario)),
            state_initial=state0,
            state_final=state,
            params=params,
            status=status,
            k_end=k_end,
            wall_time_s=wall,
            derived=derived,
        )

    # -- the kernels' records (named state) ----------------------------------------------
    @property
    def x_initial(self) -> np.ndarray:
        """The plant's initial state, a ``PLANT_STATE`` record (``x_initial["w_m"]``)."""
        return self.state_initial.plant[0]

    @property
    def x_final(self) -> np.ndarray:
        """The plant's final state, a ``PLANT_STATE`` record."""
        return self.state_final.plant[0]

    @property
    def c_final(self) -> np.ndarray:
        """Every controller-side final state (sample, model, control, MRAS, compensator),
        as one array of their raw bytes: equal arrays mean bit-identical states."""
        return np.concatenate([record_bytes(a) for a in self.state_final[1:]])

    @property
    def par(self) -> DriveParams:
        """The kernels' parameter records (:class:`~imdrive.kernels.engine.DriveParams`)."""
        return self.params

    # -- access ----------------------------------------------------------------------------
    def __getitem__(self, name: str) -> np.ndarray:
        return self.signals[name]

    @property
    def columns(self) -> list[str]:
        """The signal names, each ending with its unit (``speed_rpm``)."""
        return list(self.signals)

    @property
    def time_s(self) -> np.ndarray:
        """Times of the logged rows, s."""
        return self.signals["time_s"]

    @property
    def diverged(self) -> bool:
        """Whether the run stopped early because a state left its physical bounds."""
        return self.status != S_OK

    @property
    def lost_control_at_s(self) -> float:
        """Start of the first departure of the actual speed from its reference by more than
        ``simulation.lost_control_rpm`` that lasted ``simulation.lost_control_s`` or longer, s
        (NaN if none; on the logged samples, see :func:`imdrive.run.metrics.drive_metrics`)."""
        if "speed_ref_rpm" not in self.signals:
            return math.nan
        bound, duration = lost_control_check(self.scenario)
        s = self.signals
        return lost_control_time(
            s["time_s"], s["speed_rpm"], s["speed_ref_rpm"], bound * 30.0 / math.pi, duration
        )

    @property
    def lost_control(self) -> bool:
        """Whether the drive lost control of the speed (see :attr:`lost_control_at_s`).

        Distinct from :attr:`diverged`: the run completed (or diverged later) with finite
        states, but the speed stayed far from its reference for too long (a runaway, a
        sustained limit cycle, a stall).
        """
        return not math.isnan(self.lost_control_at_s)

    @property
    def lost_control_message(self) -> str | None:
        """One line saying when and how control was lost, or None."""
        if not self.lost_control:
            return None
        sim = self.scenario.simulation
        return (
            f"lost control at t = {self.lost_control_at_s:.6g} s: the speed stayed more than "
            f"{sim.lost_control_rpm:g} rpm from its reference for {sim.lost_control_s:g} s or "
            "longer (simulation.lost_control_rpm, lost_control_s)"
        )

    @property
    def end_time_s(self) -> float:
        """Simulated time at the end of the run (or at the divergence), s."""
        return self.k_end * self.scenario.simulation.Ts_s

    @property
    def divergence_message(self) -> str | None:
        """One line saying when and what diverged, or None."""
        if not self.diverged:
            return None
        return f"diverged at t = {self.end_time_s:.6g} s: {STATUS_TEXT[self.status]}"

    def raise_if_diverged(self) -> SimulationResult:
        """Raise :class:`~imdrive.errors.SimulationDiverged` if the run diverged.

        Returns
        -------
        SimulationResult
            This result, so scripts can write ``res = simulate(sc).raise_if_diverged()``.

        Raises
        ------
        SimulationDiverged
            The run diverged (the exception carries this result).
        """
        if self.diverged:
            from imdrive.errors import SimulationDiverged

            raise SimulationDiverged(self.end_time_s, STATUS_TEXT[self.status], self)
        return self

    def _write_exports(self, folder: Path) -> None:
        """The optional exports the scenario's ``[output]`` asks for (MAT, Parquet)."""
        from imdrive.run import export

        out = self.scenario.output
        if out.mat:
            export.to_mat(self, folder / "timeseries.mat")
        if out.parquet:
            export.to_parquet(self, folder / "timeseries.parquet")

    def to_xarray(self):
        """The signals as an ``xarray.Dataset`` (needs xarray).

        Returns
        -------
        xarray.Dataset
            One variable per signal over ``time_s``, its unit as an attribute.
        """
        from imdrive.run.export import to_xarray

        return to_xarray(self)

    def plot(self, signals: list[str] | None = None, t0: float = 0.0, t1: float | None = None):
        """A matplotlib figure of the run: one panel per signal (or per group of same unit).

        Parameters
        ----------
        signals : list of str, optional
            Column names (``res.columns``); default: speed (actual, reference, estimate),
            torque, stator current magnitude, and for vector drives e_d0 and R̂2 against R2.
        t0, t1 : float
            Time window, s.

        Returns
        -------
        matplotlib.figure.Figure
            The figure (not shown; ``fig.savefig`` or ``plt.show()``).
        """
        from imdrive.run.plots import result_figure

        return result_figure(self, signals, t0, t1)

    def to_pandas(self):
        """The signals as a pandas DataFrame.

        Returns
        -------
        pandas.DataFrame
            One column per signal, its unit in the name.
        """
        import pandas as pd

        return pd.DataFrame(self.signals)

    def window(self, t0: float, t1: float | None = None) -> dict[str, np.ndarray]:
        """Signals restricted to ``t0 <= t <= t1``.

        Parameters
        ----------
        t0 : float
            Start of the window, s.
        t1 : float, optional
            End of the window, s (default: the last row).

        Returns
        -------
        dict of str to ndarray
            Column name -> the values in the window, in the column's unit.
        """
        t = self.time_s
        sel = (t >= t0) & (t <= (t1 if t1 is not None else t[-1]))
        return {k: v[sel] for k, v in self.signals.items()}

    def mean(self, name: str, t0: float, t1: float | None = None) -> float:
        """Mean of a signal over a time window.

        Parameters
        ----------
        name : str
            Column name (``res.columns``).
        t0 : float
            Start of the window, s.
        t1 : float, optional
            End of the window, s (default: the last row).

        Returns
        -------
        float
            The mean, in the column's unit.
        """
        return float(np.mean(self.window(t0, t1)[name]))

    # -- energy ------------------------------------------------------------------------------
    def energy_balance(self) -> dict[str, float]:
        """Energies over the run (from the integrated accumulators of the plant).

        Returns
        -------
        dict of str to float
            ``input_J``, ``copper_loss_J``, ``airgap_work_J``, ``load_and_friction_work_J``,
            ``magnetic_energy_change_J``, ``kinetic_energy_change_J``, J.
        """
        x = self.x_final
        x0 = self.x_initial
        J = self.scenario.machine.J_kgm2
        p = self.params.plant[0]
        w_mag_end = magnetic_energy(p, x)
        w_mag_start = magnetic_energy(p, x0)
        return {
            "input_J": float(x["E_in"]),
            "copper_loss_J": float(x["E_cu"]),
            "airgap_work_J": float(x["E_em"]),
            "load_and_friction_work_J": float(x["E_load"]),
            "magnetic_energy_change_J": w_mag_end - w_mag_start,
            "kinetic_energy_change_J": 0.5 * J * (x["w_m"] ** 2 - x0["w_m"] ** 2),
        }

    def compensation_metrics(
        self, tol: float = CONVERGENCE_BAND, window_s: float = DEFAULT_WINDOW_S
    ) -> dict | None:
        """How the R2 compensator did; see :func:`imdrive.run.metrics.compensation_metrics`.

        Parameters
        ----------
        tol : float
            Convergence band of R2_hat around R2, a fraction of R2 (dimensionless).
        window_s : float
            Length of the steady-state window at the end of the run, s.

        Returns
        -------
        dict or None
            The metrics (units in the keys), None when the compensator is off.
        """
        return compensation_metrics(self, tol, window_s)

    def metrics(self, window_s: float = DEFAULT_WINDOW_S) -> dict:
        """This run's row of the batch table; see :func:`imdrive.run.metrics.drive_metrics`.

        Parameters
        ----------
        window_s : float
            Length of the steady-state window at the end of the run, s.

        Returns
        -------
        dict
            Metric name (unit in the name) -> value.
        """
        return drive_metrics(self, window_s)

    # -- summary and export ------------------------------------------------------------------
    @property
    def vector(self) -> bool:
        """Whether the drive is field-oriented (``drive.mode = "vector"``)."""
        return self.scenario.drive.mode == "vector"

    @property
    def extra_units(self) -> dict:
        """``{log field: (unit, scale)}`` of the estimator's own log fields."""
        return _estimator_units(self.scenario)

    def final_values(self) -> dict[str, float]:
        """Every signal at the end of the run.

        Returns
        -------
        dict of str to float
            Column name -> value at t_end (or at the divergence), in the column's unit; not
            the last logged row when ``log_every`` does not divide the number of periods.
        """
        if self.end_values is not None:
            return dict(self.end_values)
        return {k: float(v[-1]) for k, v in self.signals.items() if len(v)}

    def summary(self) -> dict:
        """What ``summary.json`` holds.

        Returns
        -------
        dict
            Scenario as run, derived quantities, versions, status, final values, energies,
            wall time (keys listed in ``docs/outputs.md``; units in the key names).
        """
        return {
            "scenario": self.scenario.to_dict(),
            "derived": {k: float(v) for k, v in self.derived.items()},
            "versions": package_versions(),
            "status": STATUS_TEXT[self.status],
            "diverged": self.diverged,
            "diverged_at_s": self.end_time_s if self.diverged else None,
            "diverged_signal": STATUS_SIGNAL.get(self.status),
            "lost_control": self.lost_control,
            "lost_control_at_s": None if not self.lost_control else self.lost_control_at_s,
            "simulated_time_s": self.end_time_s,
            "control_periods": self.k_end,
            "wall_time_s": self.wall_time_s,
            "kernel_startup_s": self.startup_s,
            "real_time_factor": (self.end_time_s / self.wall_time_s) if self.wall_time_s else None,
            "final": self.final_values(),
            "energy_J": {k: float(v) for k, v in self.energy_balance().items()},
            "compensation": self.compensation_metrics(),
            "machine_rated": _machine_rated(self.scenario.machine),
        }

    def to_csv(self, path) -> None:
        """Write the signals as CSV (header = column names with units).

        Parameters
        ----------
        path : str or pathlib.Path
            The file to write.
        """
        names = self.columns
        data = np.column_stack([self.signals[n] for n in names])
        np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")

    def save(
        self,
        out_dir,
        figures: bool | None = None,
        csv: bool | None = None,
        force: bool = False,
        report: bool | None = None,
    ) -> list[Path]:
        """Write ``timeseries.csv``, ``summary.json``, PNG figures and ``report.html`` (the
        interactive report, :mod:`imdrive.run.report`) as the folder ``out_dir``; ``figures``,
        ``csv``, ``report`` None: as the scenario's ``[output]`` says.

        The folder is replaced as a whole (:func:`imdrive._io.replace_folder`): the files are
        written into a staging folder beside it, fsynced, and the staging folder takes its
        place, so no file of an earlier result stays beside the new ones, and an interrupted
        write leaves the earlier folder as it was (staging leftovers are removed by the next
        save). An existing ``out_dir`` must be empty or an imdrive result
        (:func:`is_result_folder`) unless ``force``: other files would be deleted.

        Parameters
        ----------
        out_dir : str or pathlib.Path
            The result folder.
        figures, csv, report : bool, optional
            Write the PNG figures, ``timeseries.csv``, ``report.html``; None: as the
            scenario's ``[output]`` says.
        force : bool
            Replace a folder that holds other files.

        Returns
        -------
        list of pathlib.Path
            The files written, at their final place.

        Raises
        ------
        ConfigError
            ``out_dir`` holds other files and ``force`` is False (nothing written).
        """
        from imdrive._io import replace_folder

        out_dir = Path(out_dir)
        check_result_folder(out_dir, force)
        figures = self.scenario.output.figures if figures is None else figures
        csv = self.scenario.output.csv if csv is None else csv
        report = self.scenario.output.report if report is None else report
        with replace_folder(out_dir) as staging:
            if csv:
                self.to_csv(staging / "timeseries.csv")
            self._write_exports(staging)
            if figures:
                from imdrive.run.plots import save_figures

                save_figures(self, staging)
            if report:
                from imdrive.run.report import write_run_report

                write_run_report(self, staging / "report.html")
            (staging / "summary.json").write_text(summary_json(self.summary()))
            names = sorted(p.name for p in staging.iterdir())
        return [out_dir / n for n in names if n != "summary.json"] + [out_dir / "summary.json"]


#: The files :meth:`SimulationResult.save` may write besides PNG figures
RESULT_FILES = (
    "summary.json",
    "timeseries.csv",
    "report.html",
    "timeseries.mat",
    "timeseries.parquet",
)

NULL_NOTE = (
    "null stands for a value that is not a finite number (NaN or infinite: a diverged run's "
    "last states, a metric with no samples); JSON has no NaN or Infinity"
)


def _finite_or_null(obj):
    """``obj`` with every non-finite float replaced by None (recursively); and whether any was."""
    if isinstance(obj, float):
        return (obj, False) if math.isfinite(obj) else (None, True)
    if isinstance(obj, dict):
        out, any_null = {}, False
        for k, v in obj.items():
            out[k], n = _finite_or_null(v)
            any_null |= n
        return out, any_null
    if isinstance(obj, list | tuple):
        items = [_finite_or_null(v) for v in obj]
        return [v for v, _ in items], any(n for _, n in items)
    return obj, False


def _machine_rated(machine) -> dict | None:
    """The machine's rated point (:func:`imdrive.config.machine.rated_point`), or ``None`` when
    its circuit has none (it cannot deliver the rated power)."""
    from imdrive.config.machine import rated_point
    from imdrive.errors import ConfigError

    try:
        return rated_point(machine).to_dict()
    except ConfigError:
        return None


def summary_json(summary: dict) -> str:
    """``summary`` as strict JSON: NaN and infinities written as null, with a ``"note"`` saying
    so when there are any (most JSON parsers refuse bare ``NaN``/``Infinity``)."""
    clean, any_null = _finite_or_null(summary)
    if any_null:
        clean["note"] = NULL_NOTE
    return json.dumps(clean, indent=2, allow_nan=False) + "\n"


def is_result_folder(folder) -> bool:
    """Whether ``folder`` is missing, empty, or holds only what :meth:`SimulationResult.save`
    writes (``summary.json``, ``timeseries.csv``, ``report.html``, the exports, PNG figures,
    staging leftovers)."""
    from imdrive._io import LOCK_NAME, is_partial

    folder = Path(folder)
    if not folder.exists():
        return True
    if not folder.is_dir():
        return False
    for p in folder.iterdir():
        n = p.name
        if is_partial(n) or n == LOCK_NAME:
            continue
        if p.is_file() and (n in RESULT_FILES or n.endswith(".png")):
            continue
        return False
    return True


def check_result_folder(folder, force: bool = False) -> None:
    """Refuse (:class:`~imdrive.errors.ConfigError` on ``--out``) to replace a folder that is
    not an imdrive result, unless ``force``."""
    from imdrive.errors import ConfigError

    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ConfigError("--out", f"{folder} exists and is not a folder")
    if not force and not is_result_folder(folder):
        raise ConfigError(
            "--out",
            f"{folder} holds files that are not an imdrive result and would be deleted: choose "
            "another folder, or add --force to replace it as a whole",
        )
