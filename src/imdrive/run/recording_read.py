"""Reading a recording: Parquet, CSV or MAT, the recording's own columns or mapped ones, in
chunks with bounded memory.

:func:`open_recording` opens the file and checks its time (pass one: only the time column is
read, so every rule about time is checked, and the rows counted, before anything runs);
:meth:`RecordingFile.chunks` then gives the recording's columns (SI, named as
:data:`~imdrive.run.recording.COLUMNS`) a chunk at a time, each checked (every value finite).
Parquet is read by row groups (``pyarrow.parquet.ParquetFile.iter_batches``), CSV by blocks
(``pyarrow.csv.open_csv``); a MAT file is read whole (``scipy.io.loadmat`` has no partial
read): its size is what it holds.

MAT files: v4 to v7 (``scipy.io.loadmat``), each column a numeric vector variable at the top
level or a field of one struct variable. A v7.3 file is HDF5: read with ``h5py`` where it is
installed, refused with the reason otherwise (imdrive does not depend on it).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from imdrive.errors import ConfigError
from imdrive.run.recording_columns import COLUMNS, PERIOD_TOLERANCE, REQUIRED

#: recording columns a replay does not read: the phase currents repeat the alpha-beta ones,
#: the estimators take the commanded voltage (not the DC link), the run's own estimate is
#: what a replay gives anew
UNUSED = ("i_a_meas_A", "i_b_meas_A", "i_c_meas_A", "vdc_meas_V", "speed_est_rpm")

#: rows per chunk: a few MB per column, and numba's per-call cost negligible
CHUNK_ROWS = 1 << 17

FORMATS = {".parquet": "parquet", ".pq": "parquet", ".csv": "csv", ".mat": "mat"}


def data_file(path) -> Path:
    """The data file of ``path``: itself, or a run folder's ``recording.parquet``."""
    from imdrive.config.user_files import lexists, path_form_problem, user_file_problem

    problem = path_form_problem(path)
    if problem is not None:
        raise ConfigError("recording", problem)
    p = Path(path)
    if user_file_problem(p) is not None and lexists(p / "recording.parquet"):
        p = p / "recording.parquet"  # a run folder
    if not lexists(p):
        raise ConfigError(str(path), "no such recording (a recording.parquet or its run folder)")
    problem = user_file_problem(p, "recording")
    if problem is not None:
        raise ConfigError("recording", problem)
    return p


class TimeCheck:
    """The rules of a recording's time, checked a chunk at a time (:func:`check_time`).

    Each broken rule is a :class:`~imdrive.errors.ConfigError` naming the column and the row
    (counted from 0): every value finite; time strictly increasing; at least two rows; every
    sample period within :data:`PERIOD_TOLERANCE` of the median. Memory: the sample periods
    as float32 (4 bytes a row; their relative precision 6e-8 is far below the 1 % rule).
    """

    def __init__(self, where: str, name: str = "time_s"):
        self.where, self.name = where, name
        self._dts: list[np.ndarray] = []
        self._first = self._last = None
        self.rows = 0

    def add(self, t: np.ndarray, k0: int) -> None:
        """The next chunk ``t`` of the time column, its first row ``k0``."""
        if len(t) == 0:
            return
        check_finite(self.where, {self.name: t}, k0)
        full = t if self._last is None else np.concatenate([[self._last], t])
        dt = np.diff(full)
        bad = np.flatnonzero(dt <= 0.0)
        if bad.size:
            i = int(bad[0])
            k = k0 + i + (1 if self._last is None else 0)  # the row that breaks the rule
            how = "repeats" if dt[i] == 0.0 else "goes back from"
            raise ConfigError(
                f"{self.where}: column {self.name} row {k}",
                f"time {float(full[i + 1]):.9g} s {how} row {k - 1}'s {float(full[i]):.9g} s: "
                "time must increase strictly",
            )
        self._dts.append(dt.astype(np.float32))
        if self._first is None:
            self._first = float(t[0])
        self._last = float(t[-1])
        self.rows += len(t)

    def finish(self) -> float:
        """The mean sample period (in the column's unit), every rule checked."""
        if self.rows == 0:
            raise ConfigError(self.where, "is empty: a recording needs at least two rows")
        if self.rows < 2:
            raise ConfigError(self.where, "has one row: a recording needs at least two rows")
        dt = np.concatenate(self._dts)
        self._dts = []
        median = float(np.median(dt))
        bad = np.flatnonzero(np.abs(dt - np.float32(median)) > PERIOD_TOLERANCE * median)
        if bad.size:
            k = int(bad[0]) + 1
            raise ConfigError(
                f"{self.where}: column {self.name} row {k}",
                f"the sample period {float(dt[k - 1]):.6g} s there differs from the median "
                f"{median:.6g} s by more than {PERIOD_TOLERANCE:.0%}: a recording must be "
                "sampled at a steady rate",
            )
        return (self._last - self._first) / (self.rows - 1)


def check_time(where: str, t: np.ndarray, name: str = "time_s") -> float:
    """Check a whole time column (:class:`TimeCheck`); return its mean sample period."""
    tc = TimeCheck(where, name)
    tc.add(t, 0)
    return tc.finish()


def check_finite(where: str, cols: dict[str, np.ndarray], row0: int) -> None:
    """Every value of ``cols`` finite (one line naming the column and the row otherwise)."""
    for name, v in cols.items():
        if np.isfinite(np.add.reduce(v)):  # a NaN or inf makes the sum so: the fast path
            continue
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            k = int(bad[0])
            raise ConfigError(
                f"{where}: column {name} row {row0 + k}",
                f"is {float(v[k])}: every value must be finite",
            )


def _floats(where: str, name: str, values) -> np.ndarray:
    try:
        return np.ascontiguousarray(np.asarray(values, dtype=np.float64).reshape(-1))
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: column {name}", "must hold numbers") from None


class RecordingFile:
    """A recording file opened by :func:`open_recording` (its time read and checked).

    Attributes
    ----------
    path : pathlib.Path
    meta : dict
        ``recording.toml`` beside it (empty for a foreign recording).
    mapping : RecordingMap or None
        How its columns map to the recording's (None: they are the recording's own).
    rows : int
    period_s : float
        The mean sample period, s (every period within 1 % of the median).
    columns : list of str
        The recording columns it gives (:data:`~imdrive.run.recording.COLUMNS` names).
    """

    def __init__(self, path: Path, mapping=None):
        self.path = path
        self.mapping = mapping
        self.format = FORMATS.get(path.suffix.lower(), "parquet")
        self.meta: dict = {}
        self._mat: dict | None = None
        where = str(path)
        if path.stat().st_size == 0:
            raise ConfigError(where, "is empty: a recording needs at least two rows")
        names = self._names()
        if mapping is None:  # the columns a replay uses (not the phases nor the run's estimate)
            self._read = [n for n in names if n in COLUMNS and n not in UNUSED]
            self.columns = list(self._read)
            for name in REQUIRED:
                if name not in names:
                    raise ConfigError(
                        f"{where}: column {name}",
                        f"missing: a recording needs the columns {', '.join(REQUIRED)}",
                    )
            time_col, factor = "time_s", 1.0
        else:
            self._read = mapping.file_columns()
            for name in self._read:
                if name not in names:
                    raise ConfigError(
                        f"{where}: column {name}",
                        f"missing: the mapping {mapping.source} names it "
                        f"(the file has {', '.join(names[:12])}{'...' if len(names) > 12 else ''})",
                    )
            self.columns = list(mapping.convert({n: np.zeros(1) for n in self._read}))
            time_col, factor = mapping.signals["time"].columns[0], mapping.signals["time"].factor
        tc = TimeCheck(where, time_col)
        for k, c in self._raw([time_col]):
            tc.add(c[time_col], k)
        self.period_s = tc.finish() * factor
        self.rows = tc.rows
        self.time_column = time_col

    def column_of(self, name: str) -> str:
        """The file column(s) a recording column comes from."""
        return name if self.mapping is None else self.mapping.column_of(name)

    # --- the formats ------------------------------------------------------------------------
    def _fail(self, exc: Exception):
        kind = {"csv": "CSV", "mat": "MAT", "parquet": "Parquet"}[self.format]
        text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(str(self.path), f"is not a readable {kind} file ({text})") from None

    def _names(self) -> list[str]:
        try:
            if self.format == "parquet":
                import pyarrow.parquet as pq

                return list(pq.ParquetFile(str(self.path)).schema_arrow.names)
            if self.format == "csv":
                import pyarrow.csv as pcsv

                with pcsv.open_csv(str(self.path)) as r:
                    return list(r.schema.names)
            self._mat = read_mat(self.path)
            return list(self._mat)
        except ConfigError:
            raise
        except Exception as exc:  # pyarrow's and scipy's many error types: one line
            self._fail(exc)

    def _raw(self, names: list[str], size: int = CHUNK_ROWS) -> Iterator[tuple[int, dict]]:
        """(first row, file column -> float64 array) chunks of the columns ``names``."""
        where = str(self.path)
        if self.format == "mat":
            n = len(self._mat[names[0]])
            for k in range(0, n, size):
                yield k, {c: self._mat[c][k : k + size] for c in names}
            return
        try:
            if self.format == "parquet":
                import pyarrow.parquet as pq

                # no pre-buffering: with it pyarrow keeps what it read (memory grows with
                # the file); a 1 MiB read buffer instead. Decoded in this thread: a replay
                # reads in a thread of its own, beside the estimators (pyarrow's own
                # threads cost more CPU than they save on two cores)
                pf = pq.ParquetFile(str(self.path), pre_buffer=False, buffer_size=1 << 20)
                batches = pf.iter_batches(batch_size=size, columns=names, use_threads=False)
            else:
                import pyarrow as pa
                import pyarrow.csv as pcsv

                batches = pcsv.open_csv(
                    str(self.path),
                    read_options=pcsv.ReadOptions(block_size=size * 16 * len(names)),
                    convert_options=pcsv.ConvertOptions(
                        include_columns=names, column_types={c: pa.float64() for c in names}
                    ),
                )
            k = 0
            for b in batches:
                cols = {
                    c: _floats(where, c, b.column(c).to_numpy(zero_copy_only=False)) for c in names
                }
                yield k, cols
                k += b.num_rows
        except ConfigError:
            raise
        except Exception as exc:  # a non-numeric CSV cell, a damaged row group: one line
            if "conversion error" in str(exc).lower() or "invalid" in str(exc).lower():
                raise ConfigError(
                    where, f"a column must hold numbers ({str(exc).splitlines()[0]})"
                ) from None
            self._fail(exc)

    def chunks(self, size: int = CHUNK_ROWS) -> Iterator[tuple[int, dict]]:
        """(first row, recording column -> float64 array (SI)) chunks, every value checked
        finite (one line naming the file's column and the row otherwise)."""
        for k, raw in self._raw(self._read, size):
            check_finite(str(self.path), raw, k)
            yield k, (raw if self.mapping is None else self.mapping.convert(raw))


def read_mat(path: Path) -> dict[str, np.ndarray]:
    """The numeric vectors of a MAT file: top-level variables, or the fields of a struct.

    Raises
    ------
    ConfigError
        A v7.3 (HDF5) file without ``h5py``; a file without vectors.
    """
    import scipy.io

    try:
        major, _ = scipy.io.matlab.matfile_version(str(path))
    except Exception as exc:  # not a MAT file
        raise ConfigError(str(path), f"is not a readable MAT file ({exc})") from None
    if major == 2:
        return _read_mat_hdf5(path)
    data = scipy.io.loadmat(str(path), squeeze_me=True, struct_as_record=False)
    out = {}
    for name, v in data.items():
        if name.startswith("__"):
            continue
        if hasattr(v, "_fieldnames"):  # a struct: its fields are the columns
            out.update({f: getattr(v, f) for f in v._fieldnames})
        else:
            out[name] = v
    return {
        k: v
        for k, v in out.items()
        if isinstance(v, np.ndarray) and v.ndim == 1 and v.dtype.kind in "fiub"
    } or _no_vectors(path)


def _no_vectors(path):
    raise ConfigError(
        str(path), "holds no numeric vectors (a recording's columns, one per variable)"
    )


def _read_mat_hdf5(path: Path) -> dict[str, np.ndarray]:
    try:
        import h5py
    except ImportError:
        raise ConfigError(
            str(path),
            "is a MAT v7.3 file (HDF5), which scipy cannot read and imdrive reads only with h5py: "
            "pip install h5py, or save it from MATLAB with save(FILE, '-v7')",
        ) from None
    out = {}
    with h5py.File(str(path), "r") as f:
        for name, d in f.items():
            if (
                isinstance(d, h5py.Dataset)
                and d.dtype.kind in "fiu"
                and 1 in d.shape
                and d.ndim == 2
            ):
                out[name] = np.asarray(d).reshape(-1).astype(np.float64)
    return out or _no_vectors(path)


def open_recording(path, mapping=None) -> RecordingFile:
    """Open a recording file and check its time (pass one).

    Parameters
    ----------
    path : str or pathlib.Path
        A Parquet (``.parquet``), CSV (``.csv``) or MAT (``.mat``) file, or a run folder
        holding ``recording.parquet``.
    mapping : str, pathlib.Path, dict or RecordingMap, optional
        A mapping file (:mod:`imdrive.run.recording_map`); without one the file has the
        recording's own column names and units.

    Returns
    -------
    RecordingFile

    Raises
    ------
    ConfigError
        One line naming the file, column and row and the rule.
    """
    import tomllib

    from imdrive.config.presets import MAX_TOML_BYTES
    from imdrive.config.user_files import lexists, read_user_text
    from imdrive.run.recording_map import read_map

    p = data_file(path)
    mp = None if mapping is None else read_map(mapping)
    f = RecordingFile(p, mp)
    toml = p.with_suffix(".toml")
    if mp is None and lexists(toml):
        text = read_user_text(toml, str(toml), MAX_TOML_BYTES, "recording.toml")
        try:
            f.meta = tomllib.loads(text)
        except (tomllib.TOMLDecodeError, RecursionError) as exc:
            raise ConfigError(str(toml), f"is not valid TOML ({exc})") from None
    return f
