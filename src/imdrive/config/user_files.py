"""Paths the user gives: their mistakes are bad input, never the environment's fault.

A scenario, a machine file, a sweep file, a ``summary.json``, a recording, its map, a result
folder, a plug-in module: every file or folder a user names is checked here before it is read.
A name the file system cannot hold (a part over 255 bytes, a path over 4096), a NUL byte, a
missing file, a path through a file (``motor.toml/x``), a loop of links, a folder where a file
is expected and a special file (a FIFO would block the read, ``/dev/zero`` would never end, a
device may have side effects) are the user's input to fix: :class:`~imdrive.errors.ConfigError`
naming the field, exit 2. Before, some reached the command line's last resort as an
``OSError`` and were reported as the environment's failure (exit 4, "File name too long").
What the system does with a valid path (an I/O error, a permission) stays the reader's message.

Functions
---------
path_form_problem
    What the text of a path alone makes unusable (no system call).
user_file_problem, user_folder_problem
    What makes an existing path not a readable regular file / a folder.
read_user_file, read_user_text
    A user's file, read whole and bounded, or one ConfigError.
lexists
    Whether anything is at a path, False for one the system cannot look up.
strange_keys, redact
    What of a file's keys is foreign, and an error's text without the file's values.
is_path_error
    Whether an OSError is about a path's form or existence (the user's to fix).

It imports nothing of imdrive but :mod:`imdrive.errors`: every layer that reads a user's
file (config, run, sweep, the command line) uses it.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from imdrive.errors import ConfigError

NAME_MAX_BYTES = 255  # the longest file name on common file systems (ext4, xfs, btrfs, apfs)
PATH_MAX_BYTES = 4096

#: errno values that say the path is wrong, not the system: the user's to fix
PATH_ERRNOS = frozenset(
    code
    for code in (
        errno.ENAMETOOLONG,
        errno.ENOENT,
        errno.ENOTDIR,
        errno.ELOOP,
        errno.EISDIR,
        getattr(errno, "EILSEQ", None),  # a name the file system's encoding cannot hold
    )
    if code is not None
)


def _short(path) -> str:
    """The path for a message: a name too long to print is cut to its first 60 characters."""
    text = str(path)
    return text if len(text) <= 120 else f"{text[:60]}... ({len(text)} characters)"


def path_form_problem(path) -> str | None:
    """What the text of ``path`` alone makes unusable, or None (no system call).

    Parameters
    ----------
    path : str or os.PathLike
        The path as given.

    Returns
    -------
    str or None
        One line, e.g. ``"a part of the path is longer than 255 bytes: aaaa..."``.
    """
    try:
        text = os.fspath(path)
    except TypeError:
        return f"must be a path (a string), got {type(path).__name__}"
    if isinstance(text, bytes):  # os takes them, pathlib and imdrive's messages do not
        return "must be a path (a string), got bytes"
    if not text.strip():
        return "is empty: give a path"
    if "\0" in text:
        return f"{_short(text)!r} holds a NUL byte, which no path may"
    try:
        encoded = os.fsencode(text)
    except UnicodeError:
        return f"{_short(text)!r} holds characters the file system cannot encode"
    if len(encoded) > PATH_MAX_BYTES:
        return f"the path is longer than {PATH_MAX_BYTES} bytes: {_short(text)}"
    for part in Path(text).parts:
        if len(os.fsencode(part)) > NAME_MAX_BYTES:
            return f"a part of the path is longer than {NAME_MAX_BYTES} bytes: {part[:40]}..."
    return None


def _kind(mode: int) -> str:
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISFIFO(mode):
        return "a FIFO"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "a special file"


def describe_path_error(exc: OSError, path) -> str:
    """One line for an OSError met on a user's path (the system's reason in plain words)."""
    p = _short(path)
    code = exc.errno
    if code == errno.ENOENT:
        return f"no such file or folder: {p}"
    if code == errno.ENOTDIR:
        return f"{p}: a part of the path is a file, not a folder"
    if code == errno.ELOOP:
        return f"{p}: a loop of symbolic links"
    if code == errno.ENAMETOOLONG:
        return f"{p}: a name longer than the file system allows"
    if code == errno.EISDIR:
        return f"{p} is a folder, not a file"
    if code == errno.EACCES or code == errno.EPERM:
        return f"{p}: permission denied"
    return f"cannot read {p}: {exc.strerror or exc}"


def _stat_mode(path) -> int | str:
    """``path``'s ``st_mode``, or one line saying why it has none (its form, or the OSError of
    reaching it)."""
    problem = path_form_problem(path)
    if problem is not None:
        return problem
    try:
        return os.stat(path).st_mode
    except OSError as exc:
        return describe_path_error(exc, path)
    except ValueError as exc:  # an embedded NUL on some platforms
        return f"{_short(path)} is not a usable path ({exc})"


def user_file_problem(path, what: str = "file") -> str | None:
    """What makes ``path`` not a regular file to read, or None.

    Parameters
    ----------
    path : str or os.PathLike
        The file the user named.
    what : str
        What it should be, for the message (``"file"``, ``"recording"``).

    Returns
    -------
    str or None
        One line naming the path.
    """
    mode = _stat_mode(path)
    if isinstance(mode, str):
        return mode
    if not stat.S_ISREG(mode):
        return f"{_short(path)} is {_kind(mode)}, not a regular file ({what})"
    return None


def user_folder_problem(path) -> str | None:
    """What makes ``path`` not an existing folder to read, or None."""
    mode = _stat_mode(path)
    if isinstance(mode, str):
        return mode
    if stat.S_ISREG(mode):
        return f"{_short(path)} is a file, not a folder"
    if not stat.S_ISDIR(mode):
        return f"{_short(path)} is {_kind(mode)}, not a folder"
    return None


def read_user_file(path, field: str, max_bytes: int, what: str = "file") -> bytes:
    """The bytes of the regular file ``path`` the user named, or one ConfigError on ``field``.

    The file is opened without blocking (a FIFO cannot stall the open) and checked on the open
    descriptor (no race with a file swapped in between): a regular file of at most
    ``max_bytes``.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    field : str
        The field the error names (``"scenario"``, ``"machine.file"``).
    max_bytes : int
        The largest file accepted (B).
    what : str
        What the file should be, for the message.

    Returns
    -------
    bytes
        The whole file.
    """
    problem = path_form_problem(path)
    if problem is not None:
        raise ConfigError(field, problem)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise ConfigError(field, describe_path_error(exc, path)) from None
    except ValueError as exc:
        raise ConfigError(field, f"{_short(path)} is not a usable path ({exc})") from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise ConfigError(
                field, f"{_short(path)} is {_kind(st.st_mode)}, not a regular file ({what})"
            )
        if st.st_size > max_bytes:
            raise ConfigError(
                field, f"{_short(path)}: {st.st_size} bytes, more than a {what} holds ({max_bytes})"
            )
        chunks, size = [], 0
        while True:  # a file that grows while it is read is cut at the bound
            chunk = os.read(fd, min(1 << 20, max_bytes + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
            if size > max_bytes:
                raise ConfigError(field, f"{_short(path)}: more than a {what} holds ({max_bytes})")
        return b"".join(chunks)
    except OSError as exc:
        raise ConfigError(field, describe_path_error(exc, path)) from None
    finally:
        os.close(fd)


def read_user_text(path, field: str, max_bytes: int, what: str = "file") -> str:
    """:func:`read_user_file` decoded as UTF-8 (a byte-order mark dropped), or a ConfigError
    saying it is not UTF-8 text."""
    raw = read_user_file(path, field, max_bytes, what)
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise ConfigError(field, f"{_short(path)}: not UTF-8 text (a {what} is UTF-8)") from None


def lexists(path) -> bool:
    """Whether something (a link to nothing included) is at ``path``; False for a path the
    system cannot look up (too long, a NUL byte, through a file), which
    :func:`os.path.lexists` would raise or :meth:`pathlib.Path.exists` raises for some."""
    try:
        os.lstat(path)
    except (OSError, ValueError, TypeError):
        return False
    return True


def strange_keys(keys, known) -> tuple[list[str], int]:
    """The keys of a file that are not among ``known``: those that look like a misspelt known
    key (difflib ratio >= 0.8: the user's typo, safe to name) and the count of the others.

    A file whose keys are mostly not imdrive's is not an imdrive file (a credentials file, a
    colleague's configuration of something else): its key names and values are its owner's,
    and an error message must not print them (issue 40, class 15).

    Parameters
    ----------
    keys : iterable of str
        The file's keys.
    known : collection of str
        The keys an imdrive file of that kind may hold.

    Returns
    -------
    typos : list of str
        Unknown keys close to a known one.
    n_foreign : int
        How many unknown keys are close to none.
    """
    import difflib

    typos, n_foreign = [], 0
    for key in keys:
        if key in known:
            continue
        if difflib.get_close_matches(str(key), list(known), n=1, cutoff=0.8):
            typos.append(key)
        else:
            n_foreign += 1
    return typos, n_foreign


def redact(text: str, values) -> str:
    """``text`` with every string among ``values`` (a file's values) replaced by
    ``<the file's value>``: a rule may say what is wrong, never what the file holds."""
    strings = sorted(
        {v for v in _strings(values) if v.strip()}, key=len, reverse=True
    )  # longest first, so that a value inside another is not half replaced
    import re

    for v in strings:
        text = text.replace(repr(v), "<the file's value>")
        if len(v) >= 4:  # a shorter one would take letters out of the rule's own words
            text = re.sub(rf"(?<!\w){re.escape(v)}(?!\w)", "<the file's value>", text)
    return text


def _strings(value, depth: int = 0):
    if depth > 8:
        return
    if isinstance(value, str):
        yield value
    elif isinstance(value, dict):
        for v in value.values():
            yield from _strings(v, depth + 1)
    elif isinstance(value, list | tuple):
        for v in value:
            yield from _strings(v, depth + 1)


def is_path_error(exc: BaseException) -> bool:
    """Whether ``exc`` is an OSError about a path's form or existence (:data:`PATH_ERRNOS`)."""
    return isinstance(exc, OSError) and exc.errno in PATH_ERRNOS


#: errno values about a path's form alone: a path the user gave that fails so is theirs to fix
FORM_ERRNOS = frozenset(
    code
    for code in (
        errno.ENAMETOOLONG,
        errno.ELOOP,
        errno.ENOTDIR,
        getattr(errno, "EILSEQ", None),
    )
    if code is not None
)


def users_path_error(exc: BaseException, given) -> str | None:
    """One line when ``exc`` is an OSError about the form of a path the user gave, else None.

    The command line's last resort: an error of a path's form (too long, a loop of links, a
    file where a folder must be) that no reader caught is still the user's input, not the
    environment, when the failing path is one of the paths given (``given``: the command
    line's words, ``--set key=value`` and ``--out=value`` split at ``=``), lies inside one,
    or ends with one (a relative path resolved against a scenario's folder).

    Parameters
    ----------
    exc : BaseException
        The error.
    given : iterable of str
        The command line's arguments.

    Returns
    -------
    str or None
        ``"PATH: the system's reason"``, or None (not the user's path, not a form error).
    """
    if not isinstance(exc, OSError) or exc.errno not in FORM_ERRNOS or exc.filename is None:
        return None
    try:
        failed = os.path.normpath(os.path.abspath(os.fsdecode(exc.filename)))
    except (TypeError, ValueError):
        return None
    for word in given:
        for piece in str(word).split("="):
            if not piece.strip() or piece.startswith("-"):
                continue
            try:
                mine = os.path.normpath(os.path.abspath(piece))
                tail = os.path.normpath(piece)
            except (TypeError, ValueError):
                continue
            if (
                failed == mine
                or failed.startswith(mine + os.sep)
                or (len(tail) > 1 and failed.endswith(os.sep + tail))
            ):
                return describe_path_error(exc, exc.filename)
    return None
