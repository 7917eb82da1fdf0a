"""What every ``imdrive`` command shares: the exit codes, the argument parser's error handling,
the ``examples:`` block of a --help text and the default output folder."""

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

OUT_ROOT = Path("out")  # default output root: out/NAME, out/sweep-NAME
NAME_MAX_BYTES = 255  # longest file name on common file systems (ext4, xfs, btrfs, apfs)
PATH_MAX_BYTES = 4096


def _out_path(given: str | None, name: str, prefix: str = "") -> Path:
    """The output folder: ``--out`` if given (checked), else ``out/PREFIX+NAME``.

    The default never leaves :data:`OUT_ROOT`: ``name`` was validated by the scenario or sweep
    (a safe character set), and the resolved path is checked to be a folder inside the root.
    """
    if given is not None:
        if not given.strip():
            raise ConfigError("--out", "is empty: give a folder (or leave --out out)")
        out = Path(given)
    else:
        root = OUT_ROOT.resolve()
        out = OUT_ROOT / f"{prefix}{name}"
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


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # argparse's own errors: one line, exit 2, like ours
        self.print_usage(sys.stderr)
        print(f"imdrive: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


def _examples(*lines: str) -> str:
    """An ``examples:`` block for the end of a --help text."""
    return "examples:\n" + "\n".join(f"  {line}" for line in lines)
