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

# the columns and their rules (re-exported here, where they were first defined)
from imdrive.run.recording_columns import (
    COLUMNS,
    CONTEXT_DEFAULTS,
    MODEL_COLUMNS,
    PERIOD_TOLERANCE,
    REQUIRED,
)

__all__ = [
    "COLUMNS",
    "CONTEXT_DEFAULTS",
    "MODEL_COLUMNS",
    "PERIOD_TOLERANCE",
    "REQUIRED",
    "Recording",
    "read_recording",
    "recording_columns",
    "recording_meta",
    "write_recording",
]

SQRT3 = math.sqrt(3.0)


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
        "restart_flag": rec["restart"].astype(np.float64),
        "R1_hat_ohm": rec["R1_hat"],
        "R2_hat_ohm": rec["R2_hat"],
        "M_hat_H": rec["M_hat"],
        "R1_hat_after_ohm": rec["R1_after"],
        "R2_hat_after_ohm": rec["R2_after"],
        "t_hold_s": rec["t_hold"],
        "v_use_pu": rec["v_use"],
        "k_flux_pu": rec["k_flux"],
        "w_sl_rad_s": rec["w_sl"],
        "iq_meas_A": rec["iq_meas"],
        "L_inc_hat_H": rec["L_inc_hat"],
        "w_fb_rad_s": rec["w_fb"],
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


def parquet_options(schema, level: int | None = None) -> dict:
    """How ``recording.parquet`` is written (keywords of ``pyarrow.parquet.ParquetWriter``):
    zstd, its float columns byte-stream split and without a dictionary.

    The samples are floats with hardly a repeated value: a dictionary is built only to be
    dropped, and splitting each value's bytes into streams (exponents with exponents) is
    what lets zstd compress them. Against pyarrow's defaults (dictionary, plain), a 10^6-row
    recording is 65 MiB instead of 108, written in a fifth of the CPU time and read by a
    replay in about half (0.20 s instead of 0.38). Byte-stream split is an encoding of the
    Parquet format itself; pyarrow (and so pandas) reads it.

    Parameters
    ----------
    schema : pyarrow.Schema
    level : int, optional
        zstd's level (default: pyarrow's); a replay's estimates take the fastest, 1.
    """
    import pyarrow as pa

    split = {f.name: "BYTE_STREAM_SPLIT" for f in schema if pa.types.is_floating(f.type)}
    opts = {"compression": "zstd", "use_dictionary": False, "column_encoding": split or None}
    if level is not None:
        opts["compression_level"] = level
    return opts


def write_recording(res, folder) -> None:
    """Write ``recording.parquet`` and ``recording.toml`` of the recorded run ``res`` into
    ``folder`` (:class:`~imdrive.errors.ConfigError` if the run was not recorded)."""
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    from imdrive.config.summary_file import portable_scenario
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
    table = table.replace_schema_metadata(meta)
    path = str(folder / "recording.parquet")
    pq.write_table(table, path, **parquet_options(table.schema))
    about = recording_meta(res)
    about["scenario"] = portable_scenario(about["scenario"], folder)  # no absolute paths
    (folder / "recording.toml").write_text(dumps(about))


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
        The mean sample period, s (every period within 1 % of the median).
    """

    def __init__(self, path: Path, columns: dict, meta: dict, period_s: float):
        self.path = path
        self.columns = columns
        self.meta = meta
        self.period_s = period_s
        self.mapping = None

    @property
    def rows(self) -> int:
        """Number of rows."""
        return len(self.columns["time_s"])

    def has(self, *names: str) -> bool:
        """Whether every column of ``names`` is in the recording."""
        return all(n in self.columns for n in names)

    def column_of(self, name: str) -> str:
        """The file column(s) a recording column comes from (for messages)."""
        return name if self.mapping is None else self.mapping.column_of(name)

    def chunks(self, size: int = 1 << 18):
        """(first row, columns) slices of ``size`` rows, as a file's
        :meth:`~imdrive.run.recording_read.RecordingFile.chunks`."""
        for k in range(0, self.rows, size):
            yield k, {n: v[k : k + size] for n, v in self.columns.items()}


def read_recording(path, mapping=None) -> Recording:
    """Read and check a whole recording into memory: ``recording.parquet`` (or its run
    folder), a CSV or MAT file with the same column names, or any of them with a ``mapping``
    (:mod:`imdrive.run.recording_map`). A ``.toml`` of the same name beside it is its
    ``meta``. For a large file :func:`imdrive.run.recording_read.open_recording` reads it in
    chunks instead.

    Parameters
    ----------
    path : str or pathlib.Path
        The file or the folder holding it.
    mapping : str, pathlib.Path, dict or RecordingMap, optional
        How the file's columns map to the recording's.

    Returns
    -------
    Recording

    Raises
    ------
    ConfigError
        One line naming the file, column and row, and the rule.
    """
    from imdrive.run.recording_read import open_recording

    f = open_recording(path, mapping)
    parts = [c for _, c in f.chunks()]
    cols = {n: np.concatenate([c[n] for c in parts]) for n in parts[0]}
    rec = Recording(f.path, cols, f.meta, f.period_s)
    rec.mapping = f.mapping
    return rec
