"""A drive's recording: what its controller saw each control period, as a file, and back.

``imdrive run SCENARIO --format recording`` (or ``[output] recording = true``) writes
``recording.parquet``, one row per control period, and ``recording.toml`` beside it (units,
sample period, the run's estimator and the scenario it came from). ``imdrive replay`` reads it
back (:func:`read_recording`), checking every rule a file from elsewhere may break, and runs
speed estimators on it (:mod:`imdrive.run.replay`).

The columns (:data:`COLUMNS`) are of two kinds. The *signals* are what a drive's data log
holds: time, the measured currents, the DC-link voltage as measured, the voltage the
controller commanded, the encoder speed, the injection the controller added. The *context*
is the controller's own values its speed estimator read (angle, frequency, references, its
machine model): a replay with them runs the estimator exactly as the closed loop did; a
recording without them (a foreign one) replays with the fallbacks of :data:`CONTEXT_DEFAULTS`.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from imdrive.errors import ConfigError

SQRT3 = math.sqrt(3.0)

#: column -> (unit, meaning); the unit is also the name's suffix
COLUMNS = {
    "time_s": ("s", "the sample t_k = k Ts: the start of control period k"),
    "i_a_meas_A": ("A", "measured stator current of phase a (from the measured alpha-beta)"),
    "i_b_meas_A": ("A", "phase b"),
    "i_c_meas_A": ("A", "phase c"),
    "i_alpha_meas_A": (
        "A",
        "measured stator current, alpha (amplitude-invariant Clarke; the estimator's i_ab)",
    ),
    "i_beta_meas_A": ("A", "measured stator current, beta"),
    "vdc_meas_V": ("V", "DC-link voltage as the controller measures it"),
    "v_alpha_cmd_V": (
        "V",
        "voltage the controller commanded at t_k for [t_k, t_k + Ts), "
        "less its inverter-error compensation: what it believes reaches the "
        "terminals, the estimator's voltage at the next sample; alpha",
    ),
    "v_beta_cmd_V": ("V", "the same, beta"),
    "speed_enc_rpm": ("rpm", "the rotor's mechanical speed at t_k (an ideal encoder)"),
    "i_inj_A": ("A", "the R2 compensator's injected d-axis current this period"),
    "speed_est_rpm": ("rpm", "the run's own speed estimate after this sample's step"),
    # context: the controller's values its estimator read at t_k
    "theta_e_rad": ("rad", "the controller's field angle at t_k"),
    "w_e_rad_s": ("rad/s", "the controller's stator frequency (electrical) the estimator read"),
    "id_ref_A": ("A", "the flux-current reference of the last period"),
    "iq_ref_A": ("A", "the torque-current reference of the last period"),
    "w_ref_rad_s": ("rad/s", "the speed reference (mechanical)"),
    "hold_R1_flag": ("1", "1 where the estimator's R1 adaptation was held"),
    "R1_hat_ohm": ("ohm", "the controller's R1_hat as the estimator read it"),
    "R2_hat_ohm": ("ohm", "the controller's R2_hat as the estimator read it"),
    "M_hat_H": ("H", "the controller's magnetising inductance as the estimator read it"),
    "R1_hat_after_ohm": ("ohm", "R1_hat right after the run's estimator's step"),
    "R2_hat_after_ohm": ("ohm", "R2_hat right after the run's estimator's step"),
}

#: what a replay needs from every recording
REQUIRED = ("time_s", "i_alpha_meas_A", "i_beta_meas_A", "v_alpha_cmd_V", "v_beta_cmd_V")

#: a context column -> the value a replay takes where a recording lacks it
CONTEXT_DEFAULTS = {
    "theta_e_rad": 0.0,  # the estimator's flux error then comes in the stationary frame
    "w_e_rad_s": 0.0,
    "id_ref_A": 0.0,
    "iq_ref_A": 0.0,
    "w_ref_rad_s": 0.0,
    "i_inj_A": 0.0,
    "hold_R1_flag": 1.0,  # an R1 law cannot tell regeneration without the references: held
}

#: the model columns: all or none (with them the replayed model follows the controller's)
MODEL_COLUMNS = ("R1_hat_ohm", "R2_hat_ohm", "M_hat_H", "R1_hat_after_ohm", "R2_hat_after_ohm")

#: the sample period may vary by this much around its median
PERIOD_TOLERANCE = 0.01


def recording_columns(rec: np.ndarray, n_p: float, vdc_meas: float) -> dict[str, np.ndarray]:
    """The columns of :data:`COLUMNS` from the kernel's recording (``RECORDING`` rows).

    Parameters
    ----------
    rec : numpy.ndarray
        :data:`imdrive.kernels.recording.RECORDING` rows.
    n_p : float
        Pole pairs (the estimate is electrical).
    vdc_meas : float
        The DC-link voltage the controller measures, V.

    Returns
    -------
    dict
        Column name -> float64 array, in the order of :data:`COLUMNS`.
    """
    i_ab = rec["i_ab"]
    v = rec["v_cmd_ab"]
    rpm = 30.0 / math.pi
    cols = {
        "time_s": rec["time"],
        "i_a_meas_A": i_ab.real,
        "i_b_meas_A": -0.5 * i_ab.real + 0.5 * SQRT3 * i_ab.imag,
        "i_c_meas_A": -0.5 * i_ab.real - 0.5 * SQRT3 * i_ab.imag,
        "i_alpha_meas_A": i_ab.real,
        "i_beta_meas_A": i_ab.imag,
        "vdc_meas_V": np.full(len(rec), float(vdc_meas)),
        "v_alpha_cmd_V": v.real,
        "v_beta_cmd_V": v.imag,
        "speed_enc_rpm": rec["w_m"] * rpm,
        "i_inj_A": rec["i_inj"],
        "speed_est_rpm": rec["w_r_hat"] / n_p * rpm,
        "theta_e_rad": rec["theta_e"],
        "w_e_rad_s": rec["w_e"],
        "id_ref_A": rec["i_ref_dq"].real,
        "iq_ref_A": rec["i_ref_dq"].imag,
        "w_ref_rad_s": rec["w_ref"],
        "hold_R1_flag": rec["hold_R1"].astype(np.float64),
        "R1_hat_ohm": rec["R1_hat"],
        "R2_hat_ohm": rec["R2_hat"],
        "M_hat_H": rec["M_hat"],
        "R1_hat_after_ohm": rec["R1_after"],
        "R2_hat_after_ohm": rec["R2_after"],
    }
    return {k: np.ascontiguousarray(v, dtype=np.float64) for k, v in cols.items()}


def recording_meta(res) -> dict:
    """``recording.toml``'s content for the run ``res`` (a recorded SimulationResult)."""
    from imdrive import __version__

    sc = res.scenario
    t = res.recording["time_s"]
    return {
        "recording": {
            "format": "imdrive-recording",
            "version": 1,
            "imdrive": __version__,
            "rows": int(len(t)),
            "sample_period_s": float(sc.simulation.Ts_s),
            "estimator": str(sc.control.speed_feedback),
            "voltage": "commanded at t_k for [t_k, t_k + Ts), less the inverter-error compensation",
        },
        "units": {name: COLUMNS[name][0] for name in res.recording},
        "scenario": sc.to_dict(),
    }


def write_recording(res, folder) -> None:
    """Write ``recording.parquet`` and ``recording.toml`` of the recorded run ``res`` into
    ``folder`` (:class:`~imdrive.errors.ConfigError` if the run was not recorded)."""
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    from imdrive.config.toml_writer import dumps

    if getattr(res, "recording", None) is None:
        raise ConfigError(
            "formats",
            "recording: this run was not recorded (simulate(scenario, record=True), or "
            "[output] recording = true, or imdrive run --format recording)",
        )
    folder = Path(folder)
    table = pa.table(dict(res.recording))
    meta = dict(table.schema.metadata or {})
    meta[b"imdrive.units"] = json.dumps({n: COLUMNS[n][0] for n in res.recording}).encode()
    pq.write_table(
        table.replace_schema_metadata(meta), str(folder / "recording.parquet"), compression="zstd"
    )
    (folder / "recording.toml").write_text(dumps(recording_meta(res)))


# --- reading a recording back ---------------------------------------------------------------


class Recording:
    """A recording read and checked by :func:`read_recording`.

    Attributes
    ----------
    path : pathlib.Path
        The data file.
    columns : dict
        Column name -> float64 array (every value finite, time strictly increasing).
    meta : dict
        ``recording.toml`` beside it (empty for a foreign recording).
    period_s : float
        The median sample period, s.
    """

    def __init__(self, path: Path, columns: dict, meta: dict, period_s: float):
        self.path = path
        self.columns = columns
        self.meta = meta
        self.period_s = period_s

    @property
    def rows(self) -> int:
        """Number of rows."""
        return len(self.columns["time_s"])

    def has(self, *names: str) -> bool:
        """Whether every column of ``names`` is in the recording."""
        return all(n in self.columns for n in names)


def _data_file(path) -> Path:
    """The data file of ``path``: itself, or a run folder's ``recording.parquet``."""
    p = Path(path)
    if p.is_dir():
        p = p / "recording.parquet"
    if not p.is_file():
        raise ConfigError(str(path), "no such recording (a recording.parquet or its run folder)")
    return p


def _read_table(p: Path) -> dict[str, np.ndarray]:
    """Column name -> array of the Parquet (or, named ``*.csv``, CSV) file ``p`` (one line
    naming the file if unreadable)."""
    if p.stat().st_size == 0:
        raise ConfigError(str(p), "is empty: a recording needs at least two rows")
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    csv = p.suffix.lower() == ".csv"
    try:
        table = pcsv.read_csv(str(p)) if csv else pq.read_table(str(p))
    except Exception as exc:  # pyarrow's many error types: one line, bad input
        kind = "CSV" if csv else "Parquet"
        raise ConfigError(str(p), f"is not a readable {kind} file ({exc})") from None
    out = {}
    for name in table.column_names:
        try:
            out[name] = np.ascontiguousarray(table[name].to_numpy(), dtype=np.float64)
        except (TypeError, ValueError):
            raise ConfigError(f"{p}: column {name}", "must hold numbers") from None
    return out


def check_columns(where: str, cols: dict[str, np.ndarray]) -> float:
    """Check the rules every recording follows; return its median sample period, s.

    Rules, each broken one a :class:`~imdrive.errors.ConfigError` naming the column (and the
    row, counted from 0) and the rule: at least two rows; the :data:`REQUIRED` columns; every
    value finite; time strictly increasing; every sample period within
    :data:`PERIOD_TOLERANCE` of the median.
    """
    n = len(cols["time_s"]) if "time_s" in cols else len(next(iter(cols.values()), []))
    if n == 0:
        raise ConfigError(where, "is empty: a recording needs at least two rows")
    for name in REQUIRED:
        if name not in cols:
            raise ConfigError(
                f"{where}: column {name}",
                f"missing: a recording needs the columns {', '.join(REQUIRED)}",
            )
    if n < 2:
        raise ConfigError(where, "has one row: a recording needs at least two rows")
    for name, v in cols.items():
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            k = int(bad[0])
            raise ConfigError(
                f"{where}: column {name} row {k}", f"is {float(v[k])}: every value must be finite"
            )
    t = cols["time_s"]
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0.0)
    if bad.size:
        k = int(bad[0]) + 1
        how = "repeats" if dt[k - 1] == 0.0 else "goes back from"
        raise ConfigError(
            f"{where}: column time_s row {k}",
            f"time {float(t[k]):.9g} s {how} row {k - 1}'s {float(t[k - 1]):.9g} s: time must "
            "increase strictly",
        )
    period = float(np.median(dt))
    bad = np.flatnonzero(np.abs(dt - period) > PERIOD_TOLERANCE * period)
    if bad.size:
        k = int(bad[0]) + 1
        raise ConfigError(
            f"{where}: column time_s row {k}",
            f"the sample period {dt[k - 1]:.6g} s there differs from the median {period:.6g} s "
            f"by more than {PERIOD_TOLERANCE:.0%}: a recording must be sampled at a steady rate",
        )
    return period


def read_recording(path) -> Recording:
    """Read and check a recording: ``recording.parquet`` (or its run folder), or a CSV file
    with the same column names, with a ``.toml`` of the same name beside it if there is one.

    Parameters
    ----------
    path : str or pathlib.Path
        The file or the folder holding it.

    Returns
    -------
    Recording

    Raises
    ------
    ConfigError
        One line naming the file, column and row, and the rule (:func:`check_columns`).
    """
    import tomllib

    p = _data_file(path)
    cols = _read_table(p)
    period = check_columns(str(p), cols)
    meta = {}
    toml = p.with_suffix(".toml")
    if toml.is_file():
        try:
            meta = tomllib.loads(toml.read_text())
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise ConfigError(str(toml), f"is not valid TOML ({exc})") from None
    return Recording(p, cols, meta, period)
