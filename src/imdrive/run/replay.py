"""Replay: registered speed estimators run open loop on a drive's recording.

:func:`replay` reads a recording (:mod:`imdrive.run.recording`), builds each estimator's
records from the scenario exactly as a closed-loop run of it would
(:func:`~imdrive.run.build.build_arrays` with ``control.speed_feedback`` set to the estimator),
and runs it over the recorded rows through the registry's generic step
(:func:`imdrive.kernels.replay.replay_estimator`): the code the closed loop runs, so a
closed-loop run's recording replayed with its own estimator gives back its speed estimate,
and an estimator of the user's own (``[plugins] modules``) replays too.

Each estimator is compiled once (and cached); the recording is read once and every estimator
runs over its rows. The result holds ``speed_est_<estimator>_rpm`` and
``R2_hat_<estimator>_ohm`` per estimator (hyphens become underscores) and a summary: the
speed-estimate error against the recorded encoder (mean, RMS, largest), the status.

R2_hat: the R2-tracking law is not replayed yet. With a recording that carries the
controller's model, an estimator's ``R2_hat`` follows what the recorded controller wrote (its
R2 compensator) besides its own adaptation; without, it starts from the scenario's and only the
estimator adapts it (the AFO's and the EKF's own laws). An R2 law run on the recording belongs
where :func:`imdrive.kernels.replay.replay_estimator` writes the recorded R2_hat.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from imdrive.errors import ConfigError
from imdrive.kernels.replay import R_OK, REPLAY_ROW, replay_estimator
from imdrive.run.recording import CONTEXT_DEFAULTS, MODEL_COLUMNS, Recording, read_recording

#: the files a replay folder holds
REPLAY_FILES = ("timeseries.parquet", "summary.json")

RPM = 30.0 / math.pi


def column_name(estimator: str, quantity: str, unit: str) -> str:
    """``<quantity>_<estimator>_<unit>`` with the estimator's hyphens as underscores."""
    return f"{quantity}_{estimator.replace('-', '_')}_{unit}"


@dataclass
class ReplayResult:
    """What :func:`replay` found.

    Attributes
    ----------
    signals : dict
        ``time_s``, ``speed_enc_rpm`` (where recorded), and per estimator
        ``speed_est_<estimator>_rpm`` and ``R2_hat_<estimator>_ohm``.
    summary : dict
        The recording, the period replayed, what context it carried, and per estimator its
        status and speed-estimate error against the encoder (``summary.json``).
    """

    signals: dict
    summary: dict = field(default_factory=dict)

    def save(self, out_dir, force: bool = False) -> list[Path]:
        """Write ``timeseries.parquet`` and ``summary.json`` as the folder ``out_dir``.

        The folder is written staged and replaced as a whole (:func:`imdrive._io.replace_folder`).

        Parameters
        ----------
        out_dir : str or pathlib.Path
            The replay folder.
        force : bool
            Replace a folder that holds other files.

        Returns
        -------
        list of pathlib.Path
            The files written.

        Raises
        ------
        ConfigError
            ``out_dir`` holds other files and ``force`` is False (nothing written).
        """
        import json

        import pyarrow as pa
        import pyarrow.parquet as pq

        from imdrive._io import output_folder_problem, replace_folder
        from imdrive.run.columns import unit_of
        from imdrive.run.files import summary_json

        out_dir = Path(out_dir)
        problem = output_folder_problem(
            out_dir, lambda n: n in REPLAY_FILES, force, "an imdrive replay"
        )
        if problem is not None:
            raise ConfigError("--out", problem)
        table = pa.table({k: np.asarray(v) for k, v in self.signals.items()})
        meta = {b"imdrive.units": json.dumps({n: unit_of(n) for n in self.signals}).encode()}
        with replace_folder(out_dir) as staging:
            pq.write_table(
                table.replace_schema_metadata(meta),
                str(staging / "timeseries.parquet"),
                compression="zstd",
            )
            (staging / "summary.json").write_text(summary_json(self.summary))
        return [out_dir / n for n in REPLAY_FILES]


def _scenario(rec: Recording, scenario):
    """The scenario to replay with: the one given, or the recording's own."""
    from imdrive.config.scenario import Scenario

    if scenario is None:
        data = rec.meta.get("scenario")
        if not data:
            raise ConfigError(
                "--scenario",
                f"{rec.path} has no recording.toml naming its scenario: give the drive's "
                "scenario (its machine and controller model set the estimators' records)",
            )
        return Scenario.from_dict(data)
    if isinstance(scenario, Scenario):
        return scenario
    return Scenario.read(str(scenario))


def _scenario_of(sc, name: str):
    """The scenario with ``name`` as its estimator: ``sc`` itself for the run's own (its records
    exactly as the run's); another with the compensator off where the estimator gives no flux
    error for it (the compensator is not replayed: its R2_hat comes from the recording)."""
    own = sc.control.speed_feedback
    if own == name or (own == "measured" and name == "mras"):
        return sc
    try:
        return sc.with_overrides({"control.speed_feedback": name})
    except ConfigError:
        return sc.with_overrides({"control.speed_feedback": name, "compensator.enabled": False})


def _estimator_names(estimators, rec: Recording) -> list[str]:
    from imdrive.run.estimators import estimator_names

    if estimators is None:
        estimators = [rec.meta.get("recording", {}).get("estimator", "mras")]
    if isinstance(estimators, str):
        estimators = [e.strip() for e in estimators.split(",") if e.strip()]
    names = list(dict.fromkeys("mras" if e == "measured" else e for e in estimators))
    known = [n for n in estimator_names() if n != "measured"]
    for n in names:
        if n not in known:
            raise ConfigError("--estimators", f"no estimator {n!r} (known: {', '.join(known)})")
    if not names:
        raise ConfigError("--estimators", f"name at least one of {', '.join(known)}")
    return names


def _period(rec: Recording, Ts: float) -> float:
    """The period the estimators integrate over: the controller's where the recording is
    sampled at its rate (within 1 %), the recording's own where it is faster."""
    if rec.period_s > 1.01 * Ts:
        raise ConfigError(
            f"{rec.path}: column time_s",
            f"sample period {rec.period_s:.6g} s is longer than the controller's Ts "
            f"{Ts:.6g} s (simulation.Ts_s): a recording slower than the controller cannot be "
            "replayed (the estimators integrate over one control period)",
        )
    if rec.period_s >= 0.99 * Ts:
        return Ts
    t = rec.columns["time_s"]
    return float((t[-1] - t[0]) / (len(t) - 1))


def replay_rows(rec: Recording, sample0) -> tuple[np.ndarray, bool, list[str]]:
    """The recording as :data:`~imdrive.kernels.replay.REPLAY_ROW` rows: each row's current,
    the previous row's current and voltage (row 0: the drive's initial ``sample0``, a
    ``SAMPLE_STATE`` record), the context columns or their defaults.

    Returns
    -------
    rows : numpy.ndarray
    model_given : bool
        Whether the recording carries the controller's model (:data:`MODEL_COLUMNS`).
    defaulted : list of str
        The context columns the recording lacks (taken from :data:`CONTEXT_DEFAULTS`).
    """
    c = rec.columns
    n = rec.rows
    rows = np.zeros(n, dtype=REPLAY_ROW)
    rows["t"] = c["time_s"]
    i_ab = np.empty(n, dtype=np.complex128)
    i_ab.real = c["i_alpha_meas_A"]
    i_ab.imag = c["i_beta_meas_A"]
    v_ab = np.empty(n, dtype=np.complex128)
    v_ab.real = c["v_alpha_cmd_V"]
    v_ab.imag = c["v_beta_cmd_V"]
    rows["i_ab"] = i_ab
    rows["i_prev_ab"][1:] = i_ab[:-1]
    rows["i_prev_ab"][0] = sample0["i_prev_ab"]
    rows["v_ab"][1:] = v_ab[:-1]  # commanded at t_{k-1} for the period that ends at t_k
    rows["v_ab"][0] = sample0["v_prev_ab"]
    defaulted = [name for name in CONTEXT_DEFAULTS if name not in c]
    ctx = {name: c.get(name, np.full(n, CONTEXT_DEFAULTS[name])) for name in CONTEXT_DEFAULTS}
    rows["theta_e"] = ctx["theta_e_rad"]
    rows["w_e"] = ctx["w_e_rad_s"]
    i_ref = np.empty(n, dtype=np.complex128)
    i_ref.real = ctx["id_ref_A"]
    i_ref.imag = ctx["iq_ref_A"]
    rows["i_ref_dq"] = i_ref
    rows["w_ref"] = ctx["w_ref_rad_s"]
    rows["i_inj"] = ctx["i_inj_A"]
    rows["hold_R1"] = ctx["hold_R1_flag"] != 0.0
    model_given = rec.has(*MODEL_COLUMNS)
    if model_given:
        rows["R1_hat"] = c["R1_hat_ohm"]
        rows["R2_hat"] = c["R2_hat_ohm"]
        rows["M_hat"] = c["M_hat_H"]
        # the model the run's estimator left at the last sample; row 0: none (take the
        # recorded model as it is)
        rows["R1_prev"][1:] = c["R1_hat_after_ohm"][:-1]
        rows["R2_prev"][1:] = c["R2_hat_after_ohm"][:-1]
        rows["R1_prev"][0] = np.nan
        rows["R2_prev"][0] = np.nan
    return rows, model_given, defaulted


def _error_stats(est_rpm: np.ndarray, enc_rpm: np.ndarray) -> dict:
    e = est_rpm - enc_rpm
    return {
        "mean": float(np.mean(e)),
        "rms": float(np.sqrt(np.mean(e * e))),
        "max": float(np.max(np.abs(e))),
    }


def replay(recording, scenario=None, estimators=None, out=None, *, force=False) -> ReplayResult:
    """Run speed estimators open loop on a recording.

    Parameters
    ----------
    recording : str, pathlib.Path or Recording
        ``recording.parquet``, the run folder holding it, or a :class:`Recording`.
    scenario : str, pathlib.Path or Scenario, optional
        The drive's scenario (machine, controller model, estimator settings); default: the
        one ``recording.toml`` names.
    estimators : str or list of str, optional
        Registered estimators (``"mras,afo"`` or ``["mras", "afo"]``); default: the one the
        recorded run used.
    out : str or pathlib.Path, optional
        Write ``timeseries.parquet`` and ``summary.json`` there (:meth:`ReplayResult.save`).
    force : bool
        Replace a folder of other files.

    Returns
    -------
    ReplayResult
        Each estimator's speed estimate and R2_hat (``signals``) and its summary.

    Raises
    ------
    ConfigError
        Bad input (the recording, the scenario, an unknown estimator, ``--out``): nothing
        written.
    """
    from imdrive.run.build import build_arrays

    rec = recording if isinstance(recording, Recording) else read_recording(recording)
    sc = _scenario(rec, scenario)
    names = _estimator_names(estimators, rec)
    if out is not None:  # refused before anything runs
        from imdrive._io import output_folder_problem

        problem = output_folder_problem(out, lambda n: n in REPLAY_FILES, force, "a replay")
        if problem is not None:
            raise ConfigError("--out", problem)
    drives = {name: build_arrays(_scenario_of(sc, name)) for name in names}
    first = drives[names[0]]
    Ts = _period(rec, float(first.params.sim[0]["Ts"]))
    rows, model_given, defaulted = replay_rows(rec, first.state0.sample[0])
    n_p = float(first.params.plant[0]["n_p"])
    c = rec.columns
    signals = {"time_s": c["time_s"]}
    enc = c.get("speed_enc_rpm")
    if enc is not None:
        signals["speed_enc_rpm"] = enc
    per_est = {}
    wall = 0.0
    for name in names:
        a = drives[name]
        mdl = a.state0.model.copy()
        est = a.state0.est.copy()
        w = np.full(rec.rows, np.nan)
        R2 = np.full(rec.rows, np.nan)
        replay_estimator(a.params.est, mdl, est, rows[:0], Ts, model_given, w, R2)  # compile
        t0 = time.perf_counter()
        status, k_end = replay_estimator(a.params.est, mdl, est, rows, Ts, model_given, w, R2)
        wall += time.perf_counter() - t0
        speed = w / n_p * RPM
        signals[column_name(name, "speed_est", "rpm")] = speed
        signals[column_name(name, "R2_hat", "ohm")] = R2
        s = {"status": "ok" if status == R_OK else "diverged"}
        if status != R_OK:
            s["diverged_at_s"] = float(c["time_s"][k_end - 1])
        n_ok = k_end if status == R_OK else k_end - 1
        s["speed_error_rpm"] = (
            _error_stats(speed[:n_ok], enc[:n_ok]) if enc is not None and n_ok > 0 else None
        )
        s["R2_hat_end_ohm"] = float(R2[n_ok - 1]) if n_ok > 0 else None
        per_est[name] = s
    duration = rec.rows * Ts
    summary = {
        "recording": str(rec.path),
        "rows": rec.rows,
        "sample_period_s": rec.period_s,
        "period_replayed_s": Ts,
        "scenario": sc.name,
        "context_defaulted": defaulted,
        "model": "the recorded controller's writes" if model_given else "the scenario's",
        "R2_law": "none: R2_hat as the recorded controller wrote it, or the estimator's own",
        "wall_time_s": wall,
        "real_time_factor": duration / wall if wall > 0 else None,
        "estimators": per_est,
    }
    res = ReplayResult(signals, summary)
    if out is not None:
        res.save(out, force=force)
    return res
