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
file_path_problem, real_file, output_file
    The rule for every single file a command or function writes: a regular file or a link to
    one (written through), never a folder, a device node, a FIFO or a socket; ``output_file``
    checks it and writes atomically, the one writer of every single file at a user's path.
output_folder_problem
    The one rule for every folder a command writes: not the current folder or a parent, not
    under a file, a symbolic link kept (written through), other files refused unless forced.

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


def _remove(p: Path) -> None:
    """Delete ``p``: a symbolic link or a file is unlinked (never followed), a folder removed
    with its content. ``shutil.rmtree`` refuses a link, which used to leave it behind."""
    try:
        if p.is_symlink() or not p.is_dir():
            p.unlink(missing_ok=True)
        else:
            shutil.rmtree(p, ignore_errors=True)
    except OSError:
        pass


def remove_partials(folder) -> None:
    """Delete the temporary files and staging folders that killed writers left in ``folder``.

    Only for a folder no other process is writing to at the same time.
    """
    folder = Path(folder)
    if not folder.is_dir():
        return
    for p in folder.iterdir():
        if is_partial(p.name):
            _remove(p)


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
                _remove(p)
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

    A ``folder`` that is a symbolic link stays one: the folder it points to is replaced
    (:func:`real_folder`), and the staging folder is made beside that one.

    Parameters
    ----------
    folder : str or os.PathLike
        The folder to write; its parent is created if missing.

    Yields
    ------
    pathlib.Path
        The staging folder to write into.
    """
    folder = real_folder(folder)
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
        _remove(staging)
        _remove(old)


def real_folder(folder) -> Path:
    """``folder`` with its symbolic links resolved: where a writer that replaces the folder
    as a whole must work, so that a link the user made (``out -> /data/out``) is kept and
    written through instead of being replaced by a real folder."""
    folder = Path(folder)
    return Path(os.path.realpath(folder)) if folder.is_symlink() else folder


def file_path_problem(path) -> str | None:
    """What makes ``path`` a path no command may write a single file at, or None.

    The rule of every command that writes one file (``machine-from-nameplate --out``): a
    folder, ``.``, ``..`` or an empty name is not a file; an existing path must be a regular
    file, or a symbolic link to one (kept and written through, :func:`real_file`), never a
    device node, a FIFO or a socket (replacing ``/dev/null`` by a file breaks the system); a
    symbolic link to nothing is refused as for a folder; the folder it goes in must exist and
    not be a file; a name or path the file system cannot hold is refused.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write.

    Returns
    -------
    str or None
        One line starting with the path, e.g. ``"/dev/null is a character device, not a
        regular file"``.
    """
    import stat

    text = os.fspath(path)
    if not str(text).strip():
        return "is empty: name the file to write"
    if "\0" in str(text):
        return f"{str(text)[:60]!r} holds a NUL byte, which no path may"
    path = Path(text)
    if path.name in ("", ".", "..") or str(text).endswith(("/", os.sep)):
        return f"{path} is a folder: name the file to write"
    try:
        for part in path.parts:
            if len(os.fsencode(part)) > 255:
                return f"a part of the path is longer than 255 bytes: {part[:40]}..."
        if len(os.fsencode(str(path.absolute()))) > 4096:
            return "the path is longer than 4096 bytes"
        if path.is_symlink() and not path.exists():
            return f"{path} is a symbolic link to nothing"
        if path.exists():
            mode = os.stat(path).st_mode
            if stat.S_ISDIR(mode):
                return f"{path} is a folder: name the file to write"
            if not stat.S_ISREG(mode):
                kind = (
                    "a character device"
                    if stat.S_ISCHR(mode)
                    else "a block device"
                    if stat.S_ISBLK(mode)
                    else "a FIFO"
                    if stat.S_ISFIFO(mode)
                    else "a socket"
                    if stat.S_ISSOCK(mode)
                    else "a special file"
                )
                return f"{path} is {kind}, not a regular file: name a file to write"
        parent = real_file(path).parent
        for p in (parent, *parent.parents):
            if p.exists():
                if not p.is_dir():
                    return f"{path} is inside {p}, which is a file"
                break
        if not parent.is_dir():
            return f"{parent} is not an existing folder"
    except (OSError, ValueError) as exc:  # a NUL byte, a loop of links, a name too long
        return f"{path} is not a usable path ({getattr(exc, 'strerror', None) or exc})"
    return None


@contextmanager
def output_file(path, refuse=ValueError) -> Iterator[Path]:
    """The one writer of a single file at a path a user gave: checked, then atomic.

    ``path`` is checked by :func:`file_path_problem` before anything is written (a folder, a
    device node, a FIFO, a socket, a link to nothing, a path under a file or one too long is
    refused with ``refuse(problem)``); a symbolic link is written through
    (:func:`real_file`); the file is written under a temporary name beside it and renamed
    (:func:`atomic_path`), so a failed or killed writer leaves the old file as it was.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write.
    refuse : callable
        ``refuse(problem) -> Exception`` raised for a refused path (the caller's own error
        class, e.g. ``lambda p: ConfigError("path", p)``); default :class:`ValueError`.

    Yields
    ------
    pathlib.Path
        Where to write (the target's suffix kept, for writers that pick a format from it).
    """
    if not isinstance(path, str | os.PathLike):
        raise refuse(f"must be a file path, got {type(path).__name__}")
    problem = file_path_problem(path)
    if problem is not None:
        raise refuse(problem)
    with atomic_path(real_file(path)) as tmp:
        yield tmp


def real_file(path) -> Path:
    """``path`` with its symbolic links resolved: where a single file is written, so that a
    link the user made (``motor.toml -> machines/m1.toml``) stays a link and its target gets
    the new content (as :func:`real_folder` for a folder)."""
    path = Path(path)
    return Path(os.path.realpath(path)) if path.is_symlink() else path


def folder_path_problem(folder) -> str | None:
    """What makes ``folder`` a path no command may write a folder at, or None.

    The current folder, one of its parents, the root (a folder replaced or filled there takes
    the user's files with it); a path under a file (``file/sub``); a file; a symbolic link to
    nothing; a path the system refuses (too long, a loop of links).

    Parameters
    ----------
    folder : str or os.PathLike
        The output folder.

    Returns
    -------
    str or None
        One line starting with the path, e.g. ``"f/sub is inside /tmp/f, which is a file"``.
    """
    folder = Path(folder)
    try:
        resolved = Path(os.path.realpath(folder))
        cwd = Path.cwd().resolve()
        if resolved == cwd or resolved in cwd.parents or resolved == Path(resolved.anchor):
            return (
                f"{folder} is the current folder or one of its parents: name a folder for the "
                "results"
            )
        if folder.is_symlink() and not folder.exists():
            return f"{folder} is a symbolic link to nothing"
        if folder.exists() and not folder.is_dir():
            return f"{folder} exists and is not a folder"
        for parent in folder.absolute().parents:
            if parent.exists():
                if not parent.is_dir():
                    return f"{folder} is inside {parent}, which is a file"
                break
    except (OSError, ValueError) as exc:  # too long for the file system, a NUL byte, a loop
        return f"{folder} is not a usable path ({getattr(exc, 'strerror', None) or exc})"
    return None


def output_folder_problem(folder, owns, force: bool = False, what: str = "") -> str | None:
    """What forbids a command to write the folder ``folder``, or None: the rule every command
    that writes a folder follows (run, sweep, stability, bench-estimators, paper).

    The path must be usable (:func:`folder_path_problem`). An existing folder must be empty or
    hold only what the command itself writes (``owns(name)`` true, regular files), besides
    staging leftovers and the lock, unless ``force``: other files are someone else's and
    would be overwritten or deleted. A symbolic link to a folder is kept and written through
    (:func:`real_folder`).

    Parameters
    ----------
    folder : str or os.PathLike
        The output folder.
    owns : callable
        ``owns(name) -> bool``: whether a file of that name is one the command writes.
    force : bool
        Write into (or replace) a folder that holds other files.
    what : str
        What the command writes, for the message (``"an imdrive result"``).

    Returns
    -------
    str or None
        One line naming the path and the problem; callers raise it as bad input on ``--out``.
    """
    problem = folder_path_problem(folder)
    folder = Path(folder)
    if problem is not None or force or not folder.is_dir():
        return problem
    for p in sorted(folder.iterdir()):
        n = p.name
        if is_partial(n) or n == LOCK_NAME:
            continue
        if p.is_file() and not p.is_symlink() and owns(n):
            continue
        return (
            f"{folder} holds files that are not {what or 'what this command writes'} (e.g. "
            f"{n!r}) and would be overwritten or deleted: choose another folder, or add --force"
        )
    return None
