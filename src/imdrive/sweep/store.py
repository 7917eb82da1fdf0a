"""The sweep store: a folder of Parquet chunks, a manifest, and resuming.

``STORE/chunks/chunk-NNNNNN.parquet`` holds runs ``[N*chunk_size, (N+1)*chunk_size)``; each
chunk, then ``STORE/manifest.json``, is written atomically and durably (:mod:`imdrive._io`:
temporary file, fsync, rename, fsync of the folder), so a killed sweep leaves only whole
chunks. :func:`open_store` checks that a non-empty folder is the same sweep before resuming
it; a writer holds the store's lock (:class:`imdrive._io.FolderLock`) so two processes cannot
both write one store. On resume :meth:`Store.verify_chunks` reads every chunk back: one that
cannot be read (truncated, empty), has other columns, or does not hold exactly its runs (a
foreign file) is removed and recomputed, and so is one whose sha256 is not the one the
manifest recorded when the chunk was written (a value edited inside it), or that has none.
:meth:`Store.consolidate` checks the checksums again as it reads the chunks and writes
``STORE/runs.parquet``, every run exactly once, sorted; the manifest says ``"complete": true``
only after the table and the figures are written.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import stat
import time
from pathlib import Path

import numpy as np

from imdrive._io import (
    FolderBusy,
    FolderLock,
    atomic_path,
    atomic_write_text,
    remove_partials,
)
from imdrive.errors import ConfigError, EnvironmentFailure
from imdrive.sweep.spec import Sweep


class Store:
    """The sweep's folder: chunk files, manifest, consolidated table, figures.

    Parameters
    ----------
    root : str or pathlib.Path
        The store folder.
    """

    MANIFEST = "manifest.json"
    #: the largest manifest read (one holds a few numbers per chunk: 10 M runs in chunks of 32
    #: are about 30 MB)
    MAX_MANIFEST_BYTES = 256 * 1024**2

    def __init__(self, root: Path):
        self.root = Path(root)
        self.chunks = self.root / "chunks"
        #: chunk index -> sha256 of its file, as written (recorded in the manifest)
        self.sha256: dict[int, str] = {}

    def chunk_path(self, j: int) -> Path:
        """The file of chunk ``j``.

        Parameters
        ----------
        j : int
            Chunk index.

        Returns
        -------
        pathlib.Path
            ``chunks/chunk-NNNNNN.parquet`` under the store.
        """
        return self.chunks / f"chunk-{j:06d}.parquet"

    def completed(self) -> set[int]:
        """The chunks whose file exists.

        Returns
        -------
        set of int
            Chunk indices.
        """
        if not self.chunks.is_dir():
            return set()
        out = set()
        for p in self.chunks.iterdir():
            n = p.name
            if n.startswith("chunk-") and n.endswith(".parquet") and n[6:-8].isdigit():
                out.add(int(n[6:-8]))
        return out

    def read_manifest(self) -> dict | None:
        """The manifest, if there is one.

        Returns
        -------
        dict or None
            The manifest's content; None when the store has none.
        """
        p = self.root / self.MANIFEST
        if not p.is_file():
            return None
        try:
            st = os.stat(p)
            if not stat.S_ISREG(st.st_mode):
                raise ConfigError("--resume", f"{p}: not a regular file")
            if st.st_size > self.MAX_MANIFEST_BYTES:
                raise ConfigError("--resume", f"{p}: {st.st_size} bytes, more than a manifest")
            man = json.loads(p.read_bytes().decode("utf-8"))
        except RecursionError:
            raise ConfigError("--resume", f"{p}: JSON nested too deeply to read") from None
        except (OSError, ValueError) as exc:  # UnicodeDecodeError is a ValueError
            raise ConfigError("--resume", f"cannot read {p}: {exc}") from None
        why = _manifest_fault(man)
        if why is not None:
            raise ConfigError("--resume", f"{p} is not a sweep manifest ({why})")
        self.sha256 = {int(j): h for j, h in man.get("chunk_sha256", {}).items()}
        return man

    def write_manifest(
        self, sweep: Sweep, chunk_size: int, started: float, complete: bool = False
    ) -> None:
        """Rewrite the manifest.

        Parameters
        ----------
        sweep : Sweep
            The sweep stored here.
        chunk_size : int
            Runs per chunk.
        started : float
            When the sweep started, seconds since the epoch.
        complete : bool
            Mark the sweep complete: only once the table and figures are written.
        """
        done = sorted(self.completed())
        info = {
            "format": 1,
            "sweep": sweep.name,
            "fingerprint": sweep.fingerprint(),
            "n_runs": sweep.n_runs,
            "chunk_size": chunk_size,
            "n_chunks": sweep.n_chunks(chunk_size),
            "completed_chunks": done,
            "chunk_sha256": {str(j): self.sha256[j] for j in done if j in self.sha256},
            "complete": complete and len(done) == sweep.n_chunks(chunk_size),
            "axes": [a.name for a in sweep.axes],
            "started": started,
            "updated": time.time(),
        }
        atomic_write_text(self.root / self.MANIFEST, json.dumps(info, indent=2) + "\n")

    def write_source(self, sweep: Sweep) -> None:
        """Keep the sweep file's text beside the results (once: a resume does not rewrite it).

        Parameters
        ----------
        sweep : Sweep
            The sweep stored here.
        """
        if sweep.source and not (self.root / "sweep.toml").exists():
            atomic_write_text(self.root / "sweep.toml", sweep.source)

    def write_chunk(self, j: int, df) -> None:
        """Write chunk ``j`` atomically.

        Parameters
        ----------
        j : int
            Chunk index.
        df : pandas.DataFrame
            The chunk's table (:func:`~imdrive.sweep.run.run_chunk`).
        """
        self.sha256.pop(j, None)
        with atomic_path(self.chunk_path(j)) as tmp:
            df.to_parquet(tmp, index=False)
            digest = _sha256(tmp.read_bytes())
        self.sha256[j] = digest

    def verify_chunks(self, sweep: Sweep, chunk_size: int) -> list[str]:
        """Check every chunk file; remove the damaged ones so they are recomputed.

        A chunk is good when it can be read, has the table's columns with their types (a
        chunk written now has: :func:`chunk_dtypes`), holds exactly the runs of its index,
        each once, each run's axis values are the sweep's for that run (bit for bit: a
        value off the grid would put a wrong row in the table, or none in its heatmap), and
        its sha256 is the one the manifest recorded when it was written (a metric edited
        inside it is found only so).

        Parameters
        ----------
        sweep : Sweep
            The sweep stored here.
        chunk_size : int
            Runs per chunk.

        Returns
        -------
        list of str
            One line per removed file, saying why.
        """
        import pandas as pd

        dtypes = chunk_dtypes(sweep)
        n_chunks = sweep.n_chunks(chunk_size)
        notes = []
        for j in sorted(self.completed()):
            path = self.chunk_path(j)
            if j >= n_chunks:
                why = f"index beyond the sweep's {n_chunks} chunks"
            else:
                try:
                    raw = path.read_bytes()
                    df = pd.read_parquet(io.BytesIO(raw))
                except Exception as exc:  # any unreadable file: pyarrow raises several kinds
                    why = f"unreadable ({type(exc).__name__}: {str(exc).splitlines()[0][:120]})"
                else:
                    why = _chunk_fault(sweep, df, sweep.chunk_runs(j, chunk_size), dtypes)
                    if why is None:
                        why = self._checksum_fault(j, raw)
                    if why is None:
                        continue
            self.sha256.pop(j, None)
            path.unlink(missing_ok=True)
            notes.append(f"chunk {j} ({path.name}): {why}; removed, it will be recomputed")
        return notes

    def _checksum_fault(self, j: int, raw: bytes) -> str | None:
        """Why chunk ``j``'s bytes are not the ones written, or None."""
        if j not in self.sha256:
            return "no sha256 in the manifest (written by an earlier version, or not recorded)"
        if _sha256(raw) != self.sha256[j]:
            return "its sha256 is not the one recorded when it was written (edited)"
        return None

    def clean_partials(self) -> None:
        """Delete the temporary files of chunks and manifests that a killed sweep left."""
        for folder in (self.root, self.chunks):
            remove_partials(folder)

    def consolidate(self, sweep: Sweep, chunk_size: int):
        """Read every chunk back and write ``runs.parquet``, sorted by run.

        Parameters
        ----------
        sweep : Sweep
            The sweep stored here.
        chunk_size : int
            Runs per chunk.

        Returns
        -------
        pandas.DataFrame
            The whole table, one row per run.

        Raises
        ------
        EnvironmentFailure
            The chunks do not hold every run exactly once, or one is not as it was written
            (its sha256).
        """
        import pandas as pd

        parts = []
        for j in range(sweep.n_chunks(chunk_size)):
            raw = self.chunk_path(j).read_bytes()
            why = self._checksum_fault(j, raw)
            if why is not None:
                raise EnvironmentFailure(
                    f"{self.chunk_path(j)}: {why} while the sweep ran: resume with --resume "
                    "to verify and recompute it"
                )
            parts.append(pd.read_parquet(io.BytesIO(raw)))
        df = pd.concat(parts, ignore_index=True).sort_values("run", kind="stable")
        df = df.reset_index(drop=True)
        if len(df) != sweep.n_runs or not np.array_equal(df["run"], np.arange(sweep.n_runs)):
            raise EnvironmentFailure(
                f"{self.root}: the chunks do not hold every run exactly once (changed while "
                "the sweep ran?): resume with --resume to verify and recompute them"
            )
        with atomic_path(self.root / "runs.parquet") as tmp:
            df.to_parquet(tmp, index=False)
        return df


def _chunk_fault(sweep: Sweep, df, runs: range, dtypes: dict) -> str | None:
    """Why the chunk table ``df`` is not chunk ``runs`` of ``sweep`` as a run would write it
    (columns, their types, the runs once each, the axis values), or None when it is."""
    if set(df.columns) != set(dtypes):
        return "other columns than this sweep's table (a foreign file)"
    for name, want in dtypes.items():
        if df[name].dtype.kind != want.kind or (
            want.kind != "O" and df[name].dtype.itemsize != want.itemsize
        ):
            return f"column {name!r} is {df[name].dtype}, not {want}"
    want_runs = np.arange(runs.start, runs.stop)
    df = df.sort_values("run", kind="stable")
    if not np.array_equal(df["run"].to_numpy(), want_runs):
        return f"does not hold exactly runs {want_runs[0]}..{want_runs[-1]} once each"
    expected = sweep.inputs(runs)
    for axis in sweep.axes:
        got, want = df[axis.name].to_numpy(), expected[axis.name].to_numpy()
        same = (
            np.array_equal(got, want)
            if axis.numeric
            else [str(v) for v in got] == [str(v) for v in want]
        )
        if not same:
            return f"its {axis.name!r} values are not the sweep's for runs {runs.start}.."
    return None


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _manifest_fault(man) -> str | None:
    """What makes the decoded ``man`` not a manifest :meth:`Store.write_manifest` writes, or
    None: the fields resuming reads, with their types."""
    if not isinstance(man, dict):
        return f"a JSON {type(man).__name__}, not an object"
    if not isinstance(man.get("fingerprint"), str):
        return "no fingerprint"
    size = man.get("chunk_size")
    if isinstance(size, bool) or not isinstance(size, int) or size < 1:
        return "chunk_size is not an integer >= 1"
    started = man.get("started", 0.0)
    if isinstance(started, bool) or not isinstance(started, int | float):
        return "started is not a number"
    sums = man.get("chunk_sha256", {})
    ok = isinstance(sums, dict) and all(
        isinstance(j, str)
        and j.isascii()
        and j.isdigit()
        and isinstance(h, str)
        and len(h) == 64
        and all(c in "0123456789abcdef" for c in h)
        for j, h in sums.items()
    )
    return None if ok else "chunk_sha256 is not a table of chunk index -> sha256"


def chunk_dtypes(sweep: Sweep) -> dict:
    """Each column of a chunk of ``sweep`` and the numpy dtype a chunk read back has: ``run``
    int64, a numeric axis float64, another axis object (strings), then the batch table's."""
    from imdrive.run.batch import metrics_dtypes

    out = {"run": np.dtype(np.int64)}
    for a in sweep.axes:
        out[a.name] = np.dtype(np.float64) if a.numeric else np.dtype(object)
    out.update((k, v) for k, v in metrics_dtypes().items() if k != "drive")
    return out


def chunk_columns(sweep: Sweep) -> list[str]:
    """The columns of every chunk of ``sweep``: run, the axes, then the batch table's."""
    from imdrive.run.batch import COLUMNS

    return ["run", *(a.name for a in sweep.axes), *(c for c in COLUMNS if c != "drive")]


def lock_store(store: Store) -> FolderLock:
    """Create the store folder and take its lock (:class:`~imdrive.errors.EnvironmentFailure`
    if another process holds it)."""
    store.chunks.mkdir(parents=True, exist_ok=True)
    try:
        return FolderLock(store.root).acquire()
    except FolderBusy as exc:
        raise EnvironmentFailure(str(exc)) from None


def _is_store_entry(name: str) -> bool:
    return name != ".lock"


def open_store(sweep: Sweep, out: Path, resume: bool, chunk_size: int | None) -> tuple:
    """``(store, chunk_size, started)`` for writing ``sweep`` into the folder ``out``.

    A non-empty ``out`` needs ``resume`` and must hold the same sweep (same fingerprint), with
    the same chunk size; a resumed store keeps its chunk size and start time.
    """
    store = Store(out)
    if out.exists() and not out.is_dir():
        raise ConfigError("--out", f"{out} exists and is not a folder")
    entries = (
        sorted(p.name for p in out.iterdir() if _is_store_entry(p.name)) if out.is_dir() else []
    )
    nonempty = bool(entries)
    if nonempty and not resume:
        raise ConfigError(
            "--out",
            f"{out} exists and is not empty (e.g. {entries[0]!r}): add --resume to continue "
            "the sweep in it, or choose another folder",
        )
    man = store.read_manifest() if nonempty else None
    if nonempty and man is None:
        raise ConfigError(
            "--resume",
            f"{out} holds no {Store.MANIFEST} (e.g. {entries[0]!r}): not a sweep store",
        )
    if man is not None:
        if man.get("fingerprint") != sweep.fingerprint():
            raise ConfigError(
                "--resume",
                f"{out} holds another sweep ({man.get('sweep')!r}, different base, axes or "
                "values): use a new --out folder",
            )
        if chunk_size is not None and chunk_size != man["chunk_size"]:
            raise ConfigError(
                "--chunk-size",
                f"the store was written with chunks of {man['chunk_size']} runs: "
                "resume with the same size (or omit --chunk-size)",
            )
        chunk_size = int(man["chunk_size"])
        started = man.get("started", time.time())
    else:
        chunk_size = chunk_size or sweep.chunk_size
        started = time.time()
    return store, chunk_size, started
