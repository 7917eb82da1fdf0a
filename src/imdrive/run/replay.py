"""Replay: registered speed estimators run open loop on a drive's recording.

:func:`replay` reads a recording (:mod:`imdrive.run.recording_read`: the recording's own
Parquet, or CSV, Parquet or MAT with a mapping, :mod:`imdrive.run.recording_map`), builds each
estimator's records from the scenario exactly as a closed-loop run of it would
(:func:`~imdrive.run.build.build_arrays` with ``control.speed_feedback`` set to the estimator),
and runs it over the recorded rows through the registry's generic step
(:func:`imdrive.kernels.replay.replay_estimator`): the code the closed loop runs, so a
closed-loop run's recording replayed with its own estimator gives back its speed estimate,
and an estimator of the user's own (``[plugins] modules``) replays too.

The recording is streamed: read a chunk at a time (pass one reads only its time, to check
it and count the rows), brought to the controller's period where it is sampled faster
(:mod:`imdrive.run.decimate`), every estimator run over the chunk (its state carried to the
next), the chunk's estimates written out; the memory is bounded by the chunk, not the file.
The stages overlap in threads (:mod:`imdrive.run.replay_stream`): the next chunk is read
while the estimators run, each in a thread of its own, and the last one is written.

R2_hat: where the scenario runs an R2 law (``compensator.enabled``; the package's laws or a
plug-in) and the recording carries its excitation (the injected current, where the law
injects), each estimator runs the law too, on its own flux error, through the closed loop's
code (:mod:`imdrive.kernels.r2_tracking`): ``R2_hat_<estimator>_ohm`` is then that law's
estimate on the recorded signals, and the run's own estimator and law give back the run's
R2_hat. Otherwise (``r2_law="off"``, no law, no excitation), with a recording that carries
the controller's model, an estimator's ``R2_hat`` follows what the recorded controller wrote
besides its own adaptation; without, it starts from the scenario's and only the estimator
adapts it (the AFO's and the EKF's own laws).
"""

from __future__ import annotations

import collections
import contextlib
import math
import os
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from imdrive.errors import ConfigError, ConfigWarning
from imdrive.kernels.replay import R_OK, REPLAY_ROW, fill_rows, replay_estimator
from imdrive.run.recording import CONTEXT_DEFAULTS, MODEL_COLUMNS, REQUIRED, Recording
from imdrive.run.recording_read import CHUNK_ROWS, open_recording
from imdrive.run.replay_inputs import (
    _estimator_names,
    _limits,
    _scenario,
    _scenario_of,
    check_units,
    decimation,
    law_replayed,
)
from imdrive.run.replay_stats import ErrorStats, R2Spread
from imdrive.run.replay_stream import EstimateWriter, read_ahead

#: the files a replay folder holds
REPLAY_FILES = ("timeseries.parquet", "summary.json", "replay.png", "report.html")

RPM = 30.0 / math.pi

#: points per signal kept for the figures at most
PLOT_POINTS = 20000

#: the largest difference of the replayed law's injection from the recorded one, over its
#: amplitude, that passes without a warning: the synchronous detection's gain falls as the
#: cosine of the phase error, 5 % of the amplitude is a phase error of 3 degrees (0.1 %)
INJECTION_TOLERANCE = 0.05


def column_name(estimator: str, quantity: str, unit: str) -> str:
    """``<quantity>_<estimator>_<unit>`` with the estimator's hyphens as underscores."""
    return f"{quantity}_{estimator.replace('-', '_')}_{unit}"


class ReplayResult:
    """What :func:`replay` found.

    Attributes
    ----------
    signals : dict
        ``time_s``, ``speed_enc_rpm`` (where recorded), and per estimator
        ``speed_est_<estimator>_rpm`` and ``R2_hat_<estimator>_ohm``; read from the replay
        folder's ``timeseries.parquet`` on first use when the replay wrote one.
    summary : dict
        The recording, the period replayed, what context it carried, and per estimator its
        status and speed-estimate error against the encoder (``summary.json``).
    folder : pathlib.Path or None
        The replay folder, where it was written.
    """

    def __init__(self, signals: dict | None, summary: dict | None = None, folder=None):
        self._signals = signals
        self.summary = summary or {}
        self.folder = None if folder is None else Path(folder)
        self.plot: dict = {}  # the thinned signals the figures draw

    @property
    def signals(self) -> dict:
        if self._signals is None and self.folder is not None:
            import pyarrow.parquet as pq

            t = pq.read_table(str(self.folder / "timeseries.parquet"))
            self._signals = {n: t[n].to_numpy() for n in t.column_names}
        return self._signals

    def save(self, out_dir, force: bool = False) -> list[Path]:
        """Write the replay folder ``out_dir`` (``timeseries.parquet``, ``summary.json``,
        ``replay.png``, ``report.html``), staged and replaced as a whole
        (:func:`imdrive._io.replace_folder`).

        Raises
        ------
        ConfigError
            ``out_dir`` holds other files and ``force`` is False (nothing written).
        """
        from imdrive._io import replace_folder

        _check_out(out_dir, force)
        with replace_folder(out_dir) as staging:
            w = EstimateWriter(staging, background=False)
            w.write(self.signals)
            w.close()
            _finish(staging, self)
        return [Path(out_dir) / n for n in REPLAY_FILES]


def _check_out(out, force: bool) -> None:
    from imdrive._io import output_folder_problem

    problem = output_folder_problem(out, lambda n: n in REPLAY_FILES, force, "an imdrive replay")
    if problem is not None:
        raise ConfigError("--out", problem)


def _finish(folder: Path, res: ReplayResult) -> None:
    """``summary.json``, ``replay.png`` and ``report.html`` into ``folder``."""
    from imdrive.config.summary_file import portable_summary
    from imdrive.run.files import summary_json
    from imdrive.run.replay_report import write_figure, write_report

    (folder / "summary.json").write_text(summary_json(portable_summary(res.summary, folder)))
    if not res.plot:
        res.plot = dict(res.signals)
    write_figure(res, folder / "replay.png")
    write_report(res, folder / "report.html")


def replay_rows(cols: dict, prev: np.ndarray, rows: np.ndarray | None = None):
    """A chunk of the recording as :data:`~imdrive.kernels.replay.REPLAY_ROW` rows: each
    row's current, the previous row's current and voltage, the context columns or their
    defaults (:func:`~imdrive.kernels.replay.fill_rows`, one compiled pass).

    Parameters
    ----------
    cols : dict
        The chunk's recording columns.
    prev : numpy.ndarray, complex128[4]
        The last row before the chunk: its current, its voltage (for the first chunk the
        drive's initial ``SAMPLE_STATE``), its ``R1_hat_after`` and ``R2_hat_after`` (NaN for
        the first chunk: the recorded model taken as it is). Updated to the chunk's last row.
    rows : numpy.ndarray, optional
        A ``REPLAY_ROW`` buffer at least as long as the chunk, reused (its first rows are
        returned); default: a new one.

    Returns
    -------
    rows : numpy.ndarray
    model_given : bool
        Whether the recording carries the controller's model (:data:`MODEL_COLUMNS`).
    defaulted : list of str
        The context columns the recording lacks (taken from :data:`CONTEXT_DEFAULTS`).
    """
    c = cols
    n = len(c["time_s"])
    rows = np.empty(n, dtype=REPLAY_ROW) if rows is None or len(rows) < n else rows[:n]
    defaulted = [name for name in CONTEXT_DEFAULTS if name not in c]
    ctx = np.empty((len(CONTEXT_DEFAULTS) + 1, n))
    for j, name in enumerate(CONTEXT_DEFAULTS):
        ctx[j] = _context(c, name)
    enc = c.get("speed_enc_rpm")  # the encoder, for the R2 law's gate on a sensored drive
    ctx[-1] = 0.0 if enc is None else np.asarray(enc, dtype=float) / RPM
    model_given = all(m in c for m in MODEL_COLUMNS)
    model = np.empty((len(MODEL_COLUMNS), n if model_given else 0))
    if model_given:
        for j, name in enumerate(MODEL_COLUMNS):
            model[j] = c[name]
    f = np.ascontiguousarray
    fill_rows(
        rows, f(c["time_s"], dtype=float), f(c["i_alpha_meas_A"], dtype=float),
        f(c["i_beta_meas_A"], dtype=float), f(c["v_alpha_cmd_V"], dtype=float),
        f(c["v_beta_cmd_V"], dtype=float), ctx, model, prev,
    )  # fmt: skip
    return rows, model_given, defaulted


def _context(c: dict, name: str):
    """A context column's values, or its default: a number or another column's
    (:data:`CONTEXT_DEFAULTS`)."""
    while name not in c:
        d = CONTEXT_DEFAULTS[name]
        if not isinstance(d, str):
            return d
        name = d
    return c[name]


def _prev_row(sample0) -> np.ndarray:
    """:func:`replay_rows`'s ``prev`` before the first row: the drive's initial samples."""
    return np.array([sample0["i_prev_ab"], sample0["v_prev_ab"], np.nan, np.nan], complex)


class _Estimator:
    """One estimator's records and what it has given so far."""

    def __init__(self, name: str, a, Ts: float, model_given: bool, law: bool, n_rows: int):
        self.name = name
        self.a = a
        self.mdl = a.state0.model.copy()
        self.est = a.state0.est.copy()
        self.n_p = float(a.params.plant[0]["n_p"])
        self.Ts = Ts
        self.model_given = model_given
        P = a.params
        # the R2 law on this estimator's flux error (its own compensator records), where
        # the replay runs one and the scenario gives this estimator one
        self.law = law and bool(P.comp[0]["enabled"])
        self.inj_err = np.zeros(1)  # A, the law's injection against the recorded one
        self.inj_amp = float(P.comp[0]["inj_amp"])
        self.trk = (
            self.law, P.comp, a.state0.comp.copy(), P.tables[int(P.table_idx[0])], P.control,
            bool(P.sim[0]["sensorless"]), self.n_p, self.inj_err,
        )  # fmt: skip
        self.k = 0  # rows replayed
        self.R2 = R2Spread(n_rows)
        self.status = R_OK
        self.n_ok = 0  # rows replayed with every state finite
        self.diverged_at = None
        self.errors = ErrorStats()
        self.R2_end = None
        self.wall = 0.0  # s, its kernel's wall time (in a thread: waits for a core count)
        self.cpu = 0.0  # s, its kernel's CPU time
        w, R2 = np.zeros(0), np.zeros(0)  # compile (or load from the cache) before timing
        none = np.zeros(0, REPLAY_ROW)
        replay_estimator(P.est, self.mdl, self.est, none, Ts, model_given, w, R2, self.trk, 0)

    def run(self, rows: np.ndarray, enc) -> tuple[np.ndarray, np.ndarray]:
        """The estimator over ``rows`` (its records carried on): its speed estimate, rpm, and
        its ``R2_hat``, ohm (NaN from the row after a state stopped being finite). Called
        from a worker thread: the kernel releases the GIL, and nothing here is shared with
        the other estimators but the rows, which it only reads."""
        n = len(rows)
        if self.status != R_OK:
            return np.full(n, np.nan), np.full(n, np.nan)
        w = np.empty(n)
        R2 = np.empty(n)
        t0, c0 = time.perf_counter(), time.thread_time()
        status, k_end = replay_estimator(
            self.a.params.est, self.mdl, self.est, rows, self.Ts, self.model_given, w, R2,
            self.trk, self.k,
        )  # fmt: skip
        self.k += n
        self.wall += time.perf_counter() - t0
        self.cpu += time.thread_time() - c0
        w[k_end:] = np.nan
        R2[k_end:] = np.nan
        n_ok = k_end if status == R_OK else k_end - 1
        if status != R_OK:
            self.status = status
            self.diverged_at = float(rows["t"][k_end - 1])
        w /= self.n_p  # electrical rad/s -> mechanical rpm
        w *= RPM
        if n_ok:
            self.R2_end = float(R2[n_ok - 1])
            self.R2.add(R2[:n_ok])
            if enc is not None:
                self.errors.add(w[:n_ok] - enc[:n_ok])
        self.n_ok += n_ok
        return w, R2

    def summary(self) -> dict:
        s = {"status": "ok" if self.status == R_OK else "diverged"}
        if self.diverged_at is not None:
            s["diverged_at_s"] = self.diverged_at
        s["speed_error_rpm"] = self.errors.stats()
        s["R2_hat_end_ohm"] = self.R2_end
        s["R2_hat_ohm"] = self.R2.stats()
        s["R2_law"] = self.law
        if self.law:
            d = float(self.inj_err[0])
            s["injection_difference_A"] = d
            if self.inj_amp > 0.0 and d > INJECTION_TOLERANCE * self.inj_amp:
                s["R2_warning"] = (
                    f"the scenario's injection differs from the recorded i_inj_A by up to "
                    f"{d:.3g} A ({100.0 * d / self.inj_amp:.0f} % of its amplitude): the law "
                    "demodulates out of step with the drive's injection, and its R2_hat means "
                    "little; give the drive's injection settings"
                )
        return s


def _source(recording, mapping):
    if isinstance(recording, Recording):
        if mapping is not None:
            raise ConfigError("mapping", "applies to a file: give the recording's path")
        return recording
    if hasattr(recording, "chunks") and hasattr(recording, "period_s"):
        return recording  # a RecordingFile already opened
    return open_recording(recording, mapping)


def replay(
    recording,
    scenario=None,
    estimators=None,
    out=None,
    *,
    mapping=None,
    controller_period: str = "scenario",
    r2_law: str = "auto",
    force: bool = False,
    allow_plugins: bool | None = None,
    progress: bool | None = False,
    chunk_rows: int = CHUNK_ROWS,
) -> ReplayResult:
    """Run speed estimators open loop on a recording, streamed in chunks.

    Parameters
    ----------
    recording : str, pathlib.Path, Recording or RecordingFile
        ``recording.parquet`` or its run folder, a Parquet, CSV or MAT file, or a recording
        already read (:func:`~imdrive.run.recording.read_recording`) or opened
        (:func:`~imdrive.run.recording_read.open_recording`).
    scenario : str, pathlib.Path or Scenario, optional
        The drive's scenario (machine, controller model, estimator settings); default: the
        one ``recording.toml`` names.
    estimators : str or list of str, optional
        Registered estimators (``"mras,afo"`` or ``["mras", "afo"]``); default: the one the
        recorded run used.
    out : str or pathlib.Path, optional
        Write the replay folder there (``timeseries.parquet``, ``summary.json``,
        ``replay.png``, ``report.html``), streamed; the result's ``signals`` are then read
        back from it on first use.
    mapping : str, pathlib.Path or dict, optional
        A mapping file (``map.toml``, :mod:`imdrive.run.recording_map`) for a recording with
        other column names or units.
    controller_period : {"scenario", "file"}
        ``"scenario"``: the estimators run at ``simulation.Ts_s``, a faster recording is
        decimated to it (an integer ratio, :mod:`imdrive.run.decimate`); ``"file"``: at the
        recording's own sample period.
    r2_law : {"auto", "on", "off"}
        Run the scenario's R2 law on each estimator (module docstring): ``"auto"`` where
        the scenario's compensator is on and the recording carries its excitation, ``"on"``
        or refuse, ``"off"`` never (``R2_hat`` as the recorded controller wrote it).
    force : bool
        Replace a folder of other files.
    allow_plugins : bool, optional
        Import the plug-in modules (an estimator, an R2 law) the scenario lists: importing
        runs their code, so only where allowed (True, or ``IMDRIVE_ALLOW_PLUGINS=1``).
    progress : bool or None
        A progress bar on stderr: True, False, or None (only on a terminal).
    chunk_rows : int
        Rows read at a time.

    Returns
    -------
    ReplayResult
        Each estimator's speed estimate and R2_hat (``signals``) and its summary.

    Raises
    ------
    ConfigError
        Bad input (the recording, the mapping, units that contradict the scenario, an unknown
        estimator, ``--out``): one line, and nothing written.
    """
    from imdrive._io import replace_folder
    from imdrive._progress import Progress
    from imdrive.config.plugins import allowing_plugins
    from imdrive.run.build import build_arrays

    # a plug-in module in the scenario is imported only where allowed (config/plugins.py)
    with allowing_plugins(allow_plugins):
        rec = _source(recording, mapping)
        sc = _scenario(rec, scenario)
        if controller_period == "file":
            sc = sc.with_overrides({"simulation.Ts_s": float(rec.period_s)})
        elif controller_period != "scenario":
            raise ConfigError(
                "--controller-period", f"must be scenario or file, got {controller_period!r}"
            )
        names = _estimator_names(estimators, rec)
        if out is not None:  # refused before anything runs
            _check_out(out, force)
        drives = {name: build_arrays(_scenario_of(sc, name)) for name in names}
        first = drives[names[0]]
        Ts = float(first.params.sim[0]["Ts"])
        q = decimation(rec, Ts)
        model_given = all(m in rec.columns for m in MODEL_COLUMNS)
        law, law_note = law_replayed(r2_law, sc, first.params.comp, rec.columns)
        n_rows = rec.rows // q
        ests = [_Estimator(n, drives[n], Ts, model_given, law, n_rows) for n in names]
    # fill_rows compiled (or loaded from the cache) before the clock starts
    replay_rows({k: np.zeros(0) for k in REQUIRED}, _prev_row(first.state0.sample[0]))
    t0 = time.perf_counter()
    stage = replace_folder(out) if out is not None else contextlib.nullcontext(None)
    with stage as staging:
        sink = _Sink(ests, first.state0.sample[0], staging, max(1, n_rows // PLOT_POINTS))
        bar = Progress(rec.rows, "replay", unit="rows", enabled=progress, lines=None)
        chunks = read_ahead(_chunks(rec, chunk_rows, q, _limits(sc)))
        with bar, sink, contextlib.closing(chunks):  # closed: its thread stopped, error or not
            for n_read, cols in chunks:
                sink.emit(cols)
                bar.advance(n_read)
        res = sink.result(out)
        elapsed = time.perf_counter() - t0  # the figures and the folder not counted
        how = {
            "period_replayed_s": Ts,
            "controller_period": controller_period,
            "decimation": q,
            "model": "the recorded controller's writes" if model_given else "the scenario's",
            "R2_law": law_note,
        }
        res.summary = _summary(rec, sc, how, sink, ests, elapsed)
        for w in res.summary["warnings"]:
            warnings.warn(ConfigWarning("injection", w), stacklevel=2)
        if staging is not None:
            _finish(staging, res)
    return res


def _summary(rec, sc, how: dict, sink, ests, elapsed: float) -> dict:
    """``summary.json``: the recording, ``how`` it was replayed, each estimator's summary, the
    warnings (each estimator's law demodulating out of step with the recorded injection)."""
    Ts = how["period_replayed_s"]
    s = {
        "recording": str(rec.path),
        "rows": rec.rows,
        "sample_period_s": rec.period_s,
        "period_replayed_s": Ts,
        "controller_period": how["controller_period"],
        "decimation": how["decimation"],
        "rows_replayed": sink.done,
        "scenario_name": sc.name,
        "mapping": None if rec.mapping is None else rec.mapping.describe(),
        "context_defaulted": sink.defaulted,
        "model": how["model"],
        "R2_law": how["R2_law"],
        "wall_time_s": sum(e.wall for e in ests),  # in parallel: may exceed elapsed_s
        "estimators_cpu_s": {e.name: e.cpu for e in ests},
        "elapsed_s": elapsed,
        "real_time_factor": sink.done * Ts / elapsed if elapsed > 0 else None,
        "estimators": {e.name: e.summary() for e in ests},
        "scenario": sc.to_dict(),  # as a run's summary.json: Scenario.read takes it
    }
    s["warnings"] = [
        f"{n}: {e['R2_warning']}" for n, e in s["estimators"].items() if "R2_warning" in e
    ]
    return s


def _chunks(rec, chunk_rows: int, q: int, limits: dict):
    """(rows read, recording columns) chunks: read, every value checked, the units checked
    against the machine (:func:`check_units`), decimated where ``q > 1``. Run a chunk ahead
    in a thread of its own (:func:`~imdrive.run.replay_stream.read_ahead`)."""
    from imdrive.run.decimate import Decimator

    dec = Decimator(q) if q > 1 else None
    for k0, cols in rec.chunks(chunk_rows):
        check_units(rec, cols, k0, limits)
        yield len(cols["time_s"]), (dec.push(cols) if dec is not None else cols)


class _Sink:
    """Where the replayed chunks go: every estimator run over them, each in a thread of its
    own, the estimates written (``timeseries.parquet`` in ``staging``, by a thread of its
    own) or kept in memory, every ``stride``-th row kept for the figures.

    The estimators are not held at a barrier after each chunk: a chunk's rows are handed to
    every estimator's thread (which takes its chunks in order, its records carried on) and
    collected, in order, once every estimator is done with it, while up to :attr:`DEPTH`
    later chunks are under way; a fast estimator runs ahead instead of waiting for the slow
    one. A context manager: on leaving it every thread has finished, error or not (before a
    refusal removes the staging folder)."""

    #: chunks handed to the estimators and not yet collected, at most
    DEPTH = 2

    def __init__(self, ests, sample0, staging, stride: int):
        self.ests = ests
        self.prev = _prev_row(sample0)
        self.free: list[np.ndarray] = []  # REPLAY_ROW buffers of collected chunks, reused
        self.pending: collections.deque = collections.deque()
        self.writer = EstimateWriter(staging) if staging is not None else None
        parallel = len(ests) > 1 and (os.cpu_count() or 1) > 1
        self.threads = (
            [ThreadPoolExecutor(1, f"imdrive-replay-{e.name}") for e in ests] if parallel else None
        )
        self.memory: dict[str, list] = {}
        self.kept: dict[str, list] = {}
        self.stride = stride
        self.done = 0
        self.defaulted: list[str] = []

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        try:
            if exc[0] is None:
                while self.pending:
                    self._collect()
        finally:
            for t in self.threads or ():
                t.shutdown(wait=True, cancel_futures=True)
            if self.writer is not None:
                writer, self.writer = self.writer, None
                if exc[0] is None:
                    writer.close()
                else:
                    with contextlib.suppress(Exception):  # the error that got here is the one
                        writer.close()

    def emit(self, cols: dict) -> None:
        if not cols or len(cols["time_s"]) == 0:
            return
        n = len(cols["time_s"])
        buf = next((b for b in self.free if len(b) >= n), None)
        if buf is not None:
            self.free.remove(buf)
        rows, _, self.defaulted = replay_rows(cols, self.prev, buf)
        enc = cols.get("speed_enc_rpm")
        if self.threads is None:
            out = [e.run(rows, enc) for e in self.ests]
        else:
            out = [t.submit(e.run, rows, enc) for t, e in zip(self.threads, self.ests, strict=True)]
        self.pending.append((cols, rows if buf is None else buf, out))
        while len(self.pending) > (self.DEPTH if self.threads is not None else 0):
            self._collect()

    def _collect(self) -> None:
        """The oldest chunk's estimates, written and kept."""
        cols, buf, out = self.pending.popleft()
        if self.threads is not None:
            out = [f.result() for f in out]
        self.free.append(buf)
        enc = cols.get("speed_enc_rpm")
        sig = {"time_s": cols["time_s"]}
        if enc is not None:
            sig["speed_enc_rpm"] = enc
        for e, (speed, R2) in zip(self.ests, out, strict=True):
            sig[column_name(e.name, "speed_est", "rpm")] = speed
            sig[column_name(e.name, "R2_hat", "ohm")] = R2
        if self.writer is not None:
            self.writer.write(sig)
        else:
            for k, v in sig.items():
                self.memory.setdefault(k, []).append(v)
        first = (-self.done) % self.stride
        for k, v in sig.items():  # a copy: a view would keep the whole chunk alive
            self.kept.setdefault(k, []).append(v[first :: self.stride].copy())
        self.done += len(sig["time_s"])

    def result(self, out) -> ReplayResult:
        signals = None
        if out is None:
            signals = {k: np.concatenate(v) for k, v in self.memory.items()}
        res = ReplayResult(signals, {}, out)
        res.plot = {k: np.concatenate(v) for k, v in self.kept.items()}
        return res
