"""What every ``imdrive`` command shares: the exit codes, the argument parser's error handling,
the ``examples:`` block of a --help text, and the output folder (:func:`output_folder`: its
default name and the one rule of every command that writes a folder)."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from imdrive.errors import ConfigError

EXIT_OK = 0
EXIT_DIVERGED = 1
EXIT_BAD_INPUT = 2
EXIT_LOST_CONTROL = 3
EXIT_ENVIRONMENT = 4
EXIT_INTERNAL = 5
EXIT_NOT_IDENTIFIED = 6  # a commissioning test did not converge
EXIT_CLOSED_PIPE = 141  # stdout's reader went away (`| head`): 128 + SIGPIPE, as the shell's

OUT_ROOT = Path("out")  # default output root: out/NAME, out/sweep-NAME
NAME_MAX_BYTES = 255  # longest file name on common file systems (ext4, xfs, btrfs, apfs)
PATH_MAX_BYTES = 4096


def _out_path(given: str | None, name: str, prefix: str = "") -> Path:
    """The output folder: ``--out`` if given (checked), else ``out/PREFIX+NAME``.

    The default never leaves :data:`OUT_ROOT`: ``name`` (a preset's, a sweep's, or a file's
    own name) is made safe as a name a scenario may have (:func:`~imdrive.config.validation.slug`:
    the characters ``A-Z a-z 0-9 . _ + -``, others become ``-``), and the resolved path is
    checked to be a folder inside the root.
    """
    from imdrive.config.validation import slug

    if given is not None:
        if not given.strip():
            raise ConfigError("--out", "is empty: give a folder (or leave --out out)")
        out = Path(given)
    else:
        root = OUT_ROOT.resolve()
        out = OUT_ROOT / f"{prefix}{slug(name, default='run')}"
        inside = out.resolve()
        if inside == root or root not in inside.parents:
            raise ConfigError("name", f"{name!r} does not name a folder inside {OUT_ROOT}/")
    for part in out.parts:
        if len(os.fsencode(part)) > NAME_MAX_BYTES:
            raise ConfigError(
                "--out", f"a part of the path is longer than {NAME_MAX_BYTES} bytes: {part[:40]}..."
            )
    if len(os.fsencode(str(out.absolute()))) > PATH_MAX_BYTES:
        raise ConfigError("--out", f"the path is longer than {PATH_MAX_BYTES} bytes")
    return out


def output_folder(
    given: str | None,
    name: str = "",
    prefix: str = "",
    *,
    owns=None,
    force: bool = False,
    what: str = "",
) -> Path:
    """The folder a command writes, checked by the one rule every command follows.

    ``--out`` if given, else ``out/PREFIX+NAME`` (a safe name, :func:`_out_path`); then
    :func:`imdrive._io.output_folder_problem`: not the current folder or a parent, not under a
    file, a symbolic link kept and written through, and (with ``owns``) an existing folder
    holding only files the command writes unless ``force``.

    Parameters
    ----------
    given : str or None
        ``--out``.
    name, prefix : str
        The default folder ``out/PREFIX+NAME`` when ``given`` is None.
    owns : callable, optional
        ``owns(file name) -> bool`` for the files the command writes; None: the path alone is
        checked (a sweep store has its own rule: a manifest of the same sweep).
    force : bool
        ``--force``: write into a folder of other files.
    what : str
        What the command writes, for the message.

    Returns
    -------
    pathlib.Path
        The folder (not created).
    """
    from imdrive._io import folder_path_problem, output_folder_problem

    out = _out_path(given, name, prefix)
    if owns is None:
        problem = folder_path_problem(out)
    else:
        problem = output_folder_problem(out, owns, force, what)
    if problem is not None:
        raise ConfigError("--out", problem)
    return out


def add_force(parser, what: str) -> None:
    """The ``--force`` option of a command that writes a folder."""
    parser.add_argument(
        "--force",
        action="store_true",
        help=f"write into an --out folder that holds files other than {what}",
    )


def add_allow_plugins(parser) -> None:
    """The ``--allow-plugins`` option of a command that runs a drive (the plug-in rule of
    :mod:`imdrive.config.plugins`)."""
    parser.add_argument(
        "--allow-plugins",
        action="store_true",
        help="import the Python modules the scenario lists in [plugins] modules (their code "
        "runs; without this, or IMDRIVE_ALLOW_PLUGINS=1, such a scenario is refused)",
    )


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # argparse's own errors: one line, exit 2, like ours
        self.print_usage(sys.stderr)
        print(f"imdrive: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


def _examples(*lines: str) -> str:
    """An ``examples:`` block for the end of a --help text."""
    return "examples:\n" + "\n".join(f"  {line}" for line in lines)
