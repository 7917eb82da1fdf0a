"""Atomic writes: a file, or a folder's set of files, appears whole or not at all.

Everything imdrive writes for later reading (a run's folder, a sweep's chunks, manifest and
table) goes through this module, so an interrupted or killed process never leaves a file or a
folder that looks complete but is not.

Functions and classes
---------------------
atomic_path
    Context manager: a temporary path beside the target for writers that take a path
    (``DataFrame.to_parquet``, ``Figure.savefig``); renamed onto the target on success.
atomic_write_text, atomic_write_bytes
    Write a whole file atomically.
AtomicFolder
    Context manager: write a set of files into a staging folder, then move them into the
    target folder with the completion marker (e.g. ``summary.json``) last.
replace_folder
    Context manager: write a folder's files into a staging folder beside it, then put the
    staging folder in its place: the old folder's files are all gone, the new ones all there.
remove_partials
    Delete what killed writers left behind (temporary files and staging folders).

Notes
-----
A file is written under a temporary name in the target's own folder (``.NAME.tmp-PID-XXXXXXXX``
with the target's suffix), flushed to the disk (:func:`os.fsync`), renamed with
:func:`os.replace`, which is atomic on one file system, and the folder is fsynced so the rename
itself is durable: a reader sees the old file or the new one, never part of one, after the
process is interrupted, fails or is killed, and after a power loss (on file systems that honour
fsync).

FolderLock
    An exclusive, non-blocking lock on a folder (``fcntl.flock`` on ``FOLDER/.lock``): two
    writers of one store cannot both work. The kernel releases it when the process dies, so a
    killed writer never leaves a stale lock.

This module imports nothing of imdrive.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

PARTIAL_FOLDER_PREFIX = ".partial-"
_TMP_MARK = ".tmp-"


def _temporary_name(path: Path) -> Path:
    token = f"{os.getpid()}-{uuid.uuid4().hex[:8]}"
    return path.with_name(f".{path.stem}{_TMP_MARK}{token}{path.suffix}")


def is_partial(name: str) -> bool:
    """Whether a file or folder name is one of this module's temporary names."""
    return name.startswith(PARTIAL_FOLDER_PREFIX) or (name.startswith(".") and _TMP_MARK in name)


def fsync_file(path) -> None:
    """Flush a written file's data to the disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_folder(path) -> None:
    """Flush a folder's entries (renames, new files) to the disk; a no-op where unsupported."""
    if sys.platform == "win32":  # pragma: no cover - folders cannot be opened there
        return
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover - some file systems refuse fsync on a folder
        pass
    finally:
        os.close(fd)


@contextmanager
def atomic_path(path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it replaces ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write. Its folder must exist.

    Yields
    ------
    pathlib.Path
        Where to write. It keeps ``path``'s suffix, so writers that pick a format from the
        suffix still work. If the block raises, the temporary file is removed and ``path`` is
        left as it was.
    """
    path = Path(path)
    tmp = _temporary_name(path)
    try:
        yield tmp
        fsync_file(tmp)
        os.replace(tmp, path)
        fsync_folder(path.parent)
    finally:
        tmp.unlink(missing_ok=True)


def atomic_write_bytes(path, data: bytes) -> None:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def atomic_write_text(path, text: str, encoding: str = "utf-8") -> None:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding=encoding)


class AtomicFolder:
    """Write a set of files into ``folder``, the completion marker last.

    Use as a context manager: write every file, the marker included, into :attr:`path` (a
    staging folder inside ``folder``). On a normal exit an older marker in ``folder`` is
    removed first, then each file is moved in (:func:`os.replace`) and the marker last, so
    ``folder`` holds a marker only when every file of the same write is in place. If the block
    raises, nothing is moved. The staging folder is removed in both cases.

    Parameters
    ----------
    folder : str or os.PathLike
        The target folder, created if missing.
    marker : str
        Name of the file whose presence means "complete" (e.g. ``summary.json``); the block
        must write it.

    Attributes
    ----------
    path : pathlib.Path
        The staging folder (valid inside the ``with`` block).
    written : list of pathlib.Path
        The files moved into ``folder``, the marker last (after the block).

    Examples
    --------
    >>> with AtomicFolder(out, "summary.json") as staging:  # doctest: +SKIP
    ...     (staging.path / "data.csv").write_text(csv)
    ...     (staging.path / "summary.json").write_text(summary)
    """

    def __init__(self, folder, marker: str):
        self.folder = Path(folder)
        self.marker = marker
        self.written: list[Path] = []
        self._tmp: tempfile.TemporaryDirectory | None = None

    @property
    def path(self) -> Path:
        if self._tmp is None:
            raise RuntimeError("AtomicFolder.path is only valid inside the with block")
        return Path(self._tmp.name)

    def __enter__(self) -> AtomicFolder:
        self.folder.mkdir(parents=True, exist_ok=True)
        self._tmp = tempfile.TemporaryDirectory(dir=self.folder, prefix=PARTIAL_FOLDER_PREFIX)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        try:
            if exc_type is None:
                self._commit()
        finally:
            self._tmp.cleanup()
            self._tmp = None

    def _commit(self) -> None:
        staged = self.path
        if not (staged / self.marker).is_file():
            raise FileNotFoundError(f"{self.marker} was not written: nothing moved")
        (self.folder / self.marker).unlink(missing_ok=True)
        names = sorted(p.name for p in staged.iterdir() if p.name != self.marker)
        for name in names:
            fsync_file(staged / name)
        for name in names:
            os.replace(staged / name, self.folder / name)
            self.written.append(self.folder / name)
        fsync_folder(self.folder)  # every data file is durable before the marker appears
        fsync_file(staged / self.marker)
        os.replace(staged / self.marker, self.folder / self.marker)
        self.written.append(self.folder / self.marker)
        fsync_folder(self.folder)


def remove_partials(folder) -> None:
    """Delete the temporary files and staging folders that killed writers left in ``folder``.

    Only for a folder no other process is writing to at the same time.
    """
    folder = Path(folder)
    if not folder.is_dir():
        return
    for p in folder.iterdir():
        if not is_partial(p.name):
            continue
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)


LOCK_NAME = ".lock"


class FolderBusy(OSError):
    """Another process holds the folder's :class:`FolderLock`."""


class FolderLock:
    """An exclusive lock on ``folder`` held while a writer works in it.

    ``fcntl.flock`` on ``FOLDER/.lock``, taken without waiting: if another process (or another
    open lock in this one) holds it, :class:`FolderBusy` is raised at once. The lock is released
    on :meth:`release`, at the end of a ``with`` block, or by the kernel when the process dies;
    the ``.lock`` file itself stays (it is empty and harmless).

    Parameters
    ----------
    folder : str or os.PathLike
        An existing folder.
    """

    def __init__(self, folder):
        self.path = Path(folder) / LOCK_NAME
        self._fd: int | None = None

    def acquire(self) -> FolderLock:
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            import fcntl
        except ImportError:  # pragma: no cover - no flock (Windows): no protection
            self._fd = fd
            return self
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise FolderBusy(
                f"{self.path.parent} is in use by another imdrive process (lock {self.path})"
            ) from None
        self._fd = fd
        return self

    def release(self) -> None:
        if self._fd is not None:
            os.close(self._fd)  # closing the descriptor releases the flock
            self._fd = None

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True  # exists, owned by someone else (or cannot tell: keep its files)
    return True


def _staging_prefix(folder: Path) -> str:
    return f"{PARTIAL_FOLDER_PREFIX}{folder.name}-"


def remove_stale_staging(folder) -> None:
    """Delete the staging and old copies :func:`replace_folder` left beside ``folder``.

    Only those of writers that are no longer running (their process id is in the name), so a
    writer of the same folder that is still at work keeps its staging folder. Also removes the
    temporary files and staging folders inside ``folder`` itself (:func:`remove_partials`).
    """
    folder = Path(folder)
    parent = folder.parent
    prefix = _staging_prefix(folder)
    if parent.is_dir():
        for p in parent.iterdir():
            if not p.name.startswith(prefix):
                continue
            pid = p.name[len(prefix) :].split("-", 1)[0]
            if pid.isdigit() and not _pid_alive(int(pid)):
                shutil.rmtree(p, ignore_errors=True)
    if folder.is_dir():
        remove_partials(folder)


@contextmanager
def replace_folder(folder) -> Iterator[Path]:
    """Write a whole folder, replacing an older one as a whole.

    Yields a staging folder beside ``folder`` (``.partial-NAME-PID-XXXXXXXX`` in its parent).
    On success every file in it is fsynced, the old ``folder`` (if any) is renamed aside, the
    staging folder renamed to ``folder``, and the old copy deleted: no file of an earlier write
    survives next to the new ones. If the block raises, ``folder`` is left as it was. A writer
    killed in between leaves only ``.partial-NAME-*`` folders, which the next
    :func:`replace_folder` of the same folder removes (:func:`remove_stale_staging`).

    Parameters
    ----------
    folder : str or os.PathLike
        The folder to write; its parent is created if missing.

    Yields
    ------
    pathlib.Path
        The staging folder to write into.
    """
    folder = Path(folder)
    folder.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_staging(folder)
    token = f"{os.getpid()}-{uuid.uuid4().hex[:8]}"
    staging = folder.parent / f"{_staging_prefix(folder)}{token}"
    old = folder.parent / f"{_staging_prefix(folder)}{token}-old"
    staging.mkdir()
    try:
        yield staging
        for p in staging.iterdir():
            if p.is_file():
                fsync_file(p)
        fsync_folder(staging)
        if folder.exists():
            os.replace(folder, old)
        os.replace(staging, folder)
        fsync_folder(folder.parent)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
        shutil.rmtree(old, ignore_errors=True)
