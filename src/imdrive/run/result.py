"""The result of a run: named signals with their unit in the name, summary, export, figures.

The columns and their units are in :mod:`imdrive.run.columns`, the files of a result folder in
:mod:`imdrive.run.files` and :mod:`imdrive.run.formats` (one module per output format); this
module re-exports their names.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from imdrive.config.perunit import lost_control_rpm
from imdrive.config.plugins import module_hashes
from imdrive.config.rated import rated_point_dict
from imdrive.kernels.engine import S_CURRENT, S_NAN, S_OK, S_SPEED, DriveParams, DriveState
from imdrive.kernels.machine import magnetic_energy
from imdrive.kernels.records import record_bytes
from imdrive.run.columns import (  # noqa: F401  (re-exports)
    _DIRECT,
    LOG_UNITS,
    OPEN_LOOP_COLUMNS,
    RPM,
    SQ3_2,
    VECTOR_COLUMNS,
    Columns,
    columns_from_log,
    current_name,
    time_window,
    window_mean,
)
from imdrive.run.files import (  # noqa: F401  (re-exports)
    NULL_NOTE,
    RESULT_FILES,
    _finite_or_null,
    check_result_folder,
    is_result_folder,
    package_versions,
    summary_json,
)
from imdrive.run.formats import formats_wanted, output_formats
from imdrive.run.metrics import (
    CONVERGENCE_BAND,
    DEFAULT_WINDOW_S,
    compensation_metrics,
    drive_metrics,
    held_shares,
    lost_control_at,
    r1_sensitivity,
)
from imdrive.run.status import run_status

STATUS_TEXT = {
    S_OK: "ok",
    S_NAN: "a state became NaN or infinite",
    S_CURRENT: "stator current magnitude |i_s| exceeded simulation.divergence_current_A",
    S_SPEED: "speed |w_m| exceeded simulation.divergence_speed_rpm",
}
STATUS_SIGNAL = {S_NAN: "state", S_CURRENT: "i_s_A", S_SPEED: "speed_rpm"}


def _estimator_units(scenario) -> dict:
    """Units of the scenario's estimator's own log fields."""
    from imdrive.run.estimators import estimator_of

    return dict(estimator_of(scenario).log_units)


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
    recording : dict or None
        ``simulate(record=True)``: what the controller saw each period (imdrive.run.recording).
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
    recording: dict | None = None

    def __post_init__(self):
        # renamed columns' old names keep answering (with a DeprecationWarning) for a release
        if not isinstance(self.signals, Columns):
            self.signals = Columns(self.signals)

    @classmethod
    def from_log(
        cls, scenario, log, state0, state, params, status, k_end, wall, derived, log_units=None
    ):
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
        log_units : dict, optional
            The estimator's own log fields' ``{field: (unit, scale)}`` (``DriveArrays.log_units``;
            default: looked up from the scenario's estimator).

        Returns
        -------
        SimulationResult
            Signals converted to the exported units.
        """
        vector = scenario.drive.mode == "vector"
        units = _estimator_units(scenario) if log_units is None else dict(log_units)
        res = cls(
            scenario=scenario,
            signals=columns_from_log(log, vector, units),
            state_initial=state0,
            state_final=state,
            params=params,
            status=status,
            k_end=k_end,
            wall_time_s=wall,
            derived=derived,
        )
        res.__dict__["_extra_units"] = units  # what extra_units would look up again
        return res

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
        return self.signals[current_name(name, stacklevel=3)]

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
        return lost_control_at(self)[0]

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
            f"{lost_control_rpm(self.scenario):.3g} rpm from its reference for "
            f"{sim.lost_control_s:g} s or "
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
            The figure: shown as an image when it is the last expression of a notebook cell
            (:class:`imdrive._figure.DisplayFigure`); ``fig.savefig(path)`` writes it.
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
        Columns
            Column name -> the values in the window, in the column's unit (a ``dict``; a
            renamed column's old name answers with a ``DeprecationWarning``).
        """
        return time_window(self.signals, t0, t1)

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
        return window_mean(self.signals, name, t0, t1)

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
        # interpreted on the records (two calls): compiled, the function was a cold start's
        # entry point of its own, 0.3-0.5 s; a saturated machine's curve stays compiled
        p = self.params.plant.view(np.recarray)[0]
        w_mag_end = magnetic_energy.py_func(p, self.state_final.plant.view(np.recarray)[0])
        w_mag_start = magnetic_energy.py_func(p, self.state_initial.plant.view(np.recarray)[0])
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

    @property
    def verdict(self) -> dict:
        """This run's status: ``"ok"`` or why not (:func:`imdrive.run.status.run_status`)."""
        if "_verdict" not in self.__dict__:
            self.__dict__["_verdict"] = run_status(
                self.metrics(), held_shares(self), r1_sensitivity(self)
            )
        return dict(self.__dict__["_verdict"])

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
        units = self.__dict__.get("_extra_units")
        if units is None:
            units = self.__dict__["_extra_units"] = _estimator_units(self.scenario)
        return units

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

        ``"plugins"`` maps each plug-in module of the scenario to the sha256 of its file, so
        a rerun of the ``summary.json`` says when a module has changed since.

        Returns
        -------
        dict
            Scenario as run, derived quantities, versions, status, final values, energies,
            wall time (keys listed in ``docs/outputs.md``; units in the key names).
        """
        return {
            "scenario": self.scenario.to_dict(),
            "derived": {k: float(v) for k, v in self.derived.items()},
            "resolved": self._resolved_defaults(),
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
            "machine_rated": rated_point_dict(self.scenario.machine),
            "verdict": self.verdict,
            "plugins": module_hashes(self.scenario.plugins.modules),
        }

    def _resolved_defaults(self) -> dict:
        """The value each unset scenario-dependent setting took in this run (dotted key ->
        value; :func:`imdrive.config.resolved.resolved_defaults`), only those left unset."""
        from imdrive.config.resolved import unset_resolved_defaults

        return unset_resolved_defaults(self.scenario)

    def to_csv(self, path) -> None:
        """Write the signals as CSV (header = column names with units).

        Parameters
        ----------
        path : str or pathlib.Path
            The file to write.
        """
        from imdrive.run.formats.csv import to_csv

        to_csv(self, path)

    def save(
        self,
        out_dir,
        figures: bool | None = None,
        csv: bool | None = None,
        force: bool = False,
        report: bool | None = None,
        formats=None,
    ) -> list[Path]:
        """Write ``summary.json`` and every output format the scenario's ``[output]`` turns on
        (:mod:`imdrive.run.formats`: ``timeseries.csv``, PNG figures, ``report.html``, the MAT
        and Parquet exports) as the folder ``out_dir``; ``figures``, ``csv``, ``report`` given:
        they override ``[output]``.

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
        formats : iterable of str, optional
            Exactly these output formats (names of :func:`imdrive.run.formats.output_formats`:
            ``"csv"``, ``"mat"``, ``"parquet"``, ``"figures"``, ``"report"``), whatever
            ``[output]`` says; ``summary.json`` is always written.

        Returns
        -------
        list of pathlib.Path
            The files written, at their final place.

        Raises
        ------
        ConfigError
            ``out_dir`` holds other files and ``force`` is False, or an unknown format
            (nothing written).
        """
        from imdrive._io import replace_folder
        from imdrive.config.summary_file import portable_summary

        check_result_folder(out_dir, force)
        out_dir = Path(out_dir)
        output = self.scenario.output
        wanted = {f.key: getattr(output, f.key) for f in output_formats()}
        if formats is not None:
            wanted = formats_wanted(formats)
        for key, given in (("figures", figures), ("csv", csv), ("report", report)):
            if given is not None:
                wanted[key] = given
        with replace_folder(out_dir) as staging:
            for fmt in output_formats():  # every registered format its [output] key turns on
                if wanted[fmt.key]:
                    fmt.write(self, staging)
            summary = portable_summary(self.summary(), staging)  # staging: beside out_dir
            (staging / "summary.json").write_text(summary_json(summary))
            names = sorted(p.name for p in staging.iterdir())
        return [out_dir / n for n in names if n != "summary.json"] + [out_dir / "summary.json"]


#: The files :meth:`SimulationResult.save` may write besides PNG figures
