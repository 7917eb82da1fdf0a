"""Hostile inputs shared by the property-based tests (tests/package/test_properties.py) and
the campaign (tests/hostile_campaign.py): values for every flag of every command, read from
the argument parser itself, hostile paths, and hostile arguments for the public API.

Outcomes (:func:`run_cli`, :func:`call_api`): ``"refused"`` (exit 2 with one line
``imdrive: error: ...``, or a :class:`~imdrive.errors.ConfigError` in one line), ``"correct"``
(a documented outcome: exit 0, 1 or 3, or a value returned), or a failure described in one
line (another exit code, a traceback, more than one error line, another exception, a hang,
something written where a refusal was expected).
"""

from __future__ import annotations

import argparse
import io
import os
import signal
import socket
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from pathlib import Path

#: strings a flag's value may be (numbers in text, separators, control characters, long)
TEXTS = (
    "", " ", ",", ":", "::", "0", "-0", "1", "-1", "2", "1e-300", "-1e-300", "1e308", "-1e308",
    "1e999", "nan", "NaN", "inf", "-inf", "0x10", "1_000", "½", "١", "abc", "a,b", "0:1e308:2",
    "0:1:0", "1:0:3", "0:1:1e9", "5:5:1", "mras,", ",mras", "mras,mras", "nosuch", "sensorless",
    "true", "[1]", "{}", "a" * 300, "\t", "\n", "x\ny", "--out", "-q", "é" * 90, "\x1b[31m",
)  # fmt: skip


def path_kinds() -> tuple[str, ...]:
    return (
        "empty", ".", "..", "file", "under-a-file", "fifo", "socket", "device", "dangling",
        "too-long", "folder", "foreign-folder", "loop",
    )  # fmt: skip


def make_path(tmp: Path, kind: str, suffix: str = "") -> str:
    """A hostile path of ``kind`` inside ``tmp`` (created as needed)."""
    tmp.mkdir(parents=True, exist_ok=True)
    if kind == "empty":
        return ""
    if kind in (".", ".."):
        return kind
    if kind == "file":
        p = tmp / f"notes{suffix or '.txt'}"
        p.write_text("mine\n")
        return str(p)
    if kind == "under-a-file":
        (tmp / "notes.txt").write_text("mine\n")
        return str(tmp / "notes.txt" / f"sub{suffix}")
    if kind == "fifo":
        p = tmp / f"fifo{suffix}"
        if not p.exists():
            os.mkfifo(p)
        return str(p)
    if kind == "socket":
        p = tmp / f"sock{suffix}"
        if not p.exists():
            s = socket.socket(socket.AF_UNIX)
            s.bind(str(p))
            s.close()
        return str(p)
    if kind == "device":
        p = tmp / f"zero{suffix}"
        if not p.is_symlink():
            p.symlink_to("/dev/zero")
        return str(p)
    if kind == "dangling":
        p = tmp / f"dangling{suffix}"
        if not p.is_symlink():
            p.symlink_to(tmp / "nothing-here")
        return str(p)
    if kind == "loop":
        p = tmp / f"loop{suffix}"
        if not p.is_symlink():
            p.symlink_to(p)
        return str(p)
    if kind == "too-long":
        return str(tmp / ("a" * 300 + suffix))
    if kind == "folder":
        p = tmp / f"folder{suffix}"
        p.mkdir(exist_ok=True)
        return str(p)
    if kind == "foreign-folder":
        p = tmp / "thesis"
        p.mkdir(exist_ok=True)
        (p / "thesis.tex").write_text("mine\n")
        return str(p)
    raise ValueError(kind)


def commands() -> dict[str, argparse.ArgumentParser]:
    """Every sub-command's parser, read from :func:`imdrive.cli.build_parser`."""
    from imdrive.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def flags(parser: argparse.ArgumentParser) -> list[tuple[str, bool]]:
    """``(option, takes_a_value)`` of every optional flag of ``parser`` (help aside)."""
    out = []
    for a in parser._actions:
        if not a.option_strings or isinstance(a, argparse._HelpAction):
            continue
        out.append((max(a.option_strings, key=len), a.nargs != 0))
    return out


def positionals(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in parser._actions if not a.option_strings]


#: what each command writes to, and whether a hostile one must be refused before any work
WRITERS = {
    "run", "sweep", "stability", "bench-estimators", "compare", "paper", "replay",
    "commission", "machine-from-nameplate",
}  # fmt: skip


class Hang(Exception):
    """The call took longer than its bound."""


@contextmanager
def time_bound(seconds: float):
    """Raise :class:`Hang` in the main thread after ``seconds`` (SIGALRM)."""

    def _alarm(signum, frame):
        raise Hang(f"no answer in {seconds:g} s")

    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def run_cli(argv: list[str], bound_s: float = 120.0) -> tuple[str, str]:
    """Run ``imdrive ARGV`` in this process: ``(outcome, detail)`` (module docstring)."""
    from imdrive.cli import main

    out, err = io.StringIO(), io.StringIO()
    try:
        with time_bound(bound_s), redirect_stdout(out), redirect_stderr(err):
            rc = main(list(argv))
    except SystemExit as exc:  # argparse's own refusals (our parser prints one line)
        rc = exc.code
    except Hang as exc:
        return "failure", f"hang: {exc}"
    except BaseException as exc:  # noqa: BLE001 - anything escaping main() is a failure
        return "failure", f"escaped main(): {type(exc).__name__}: {str(exc)[:200]}"
    text = err.getvalue()
    errors = [x for x in text.splitlines() if x.startswith("imdrive: error:")]
    if "Traceback" in text or "Exception ignored" in text:
        return "failure", f"traceback (exit {rc})"
    if rc == 2:
        if len(errors) != 1:
            return "failure", f"exit 2 with {len(errors)} error lines"
        return "refused", errors[0]
    if rc in (0, 1, 3, 6, 141):
        return "correct", f"exit {rc}"
    return "failure", f"exit {rc}: {errors[-1] if errors else text.strip()[-200:]}"


def call_api(fn, *args, bound_s: float = 60.0, **kwargs) -> tuple[str, str]:
    """Call ``fn``: ``(outcome, detail)``; a returned float that is NaN is a failure."""
    import math

    from imdrive.errors import ConfigError, SimulationDiverged

    try:
        with time_bound(bound_s):
            value = fn(*args, **kwargs)
    except ConfigError as exc:
        if "\n" in str(exc):
            return "failure", "ConfigError over several lines"
        return "refused", str(exc)[:200]
    except SimulationDiverged:
        return "correct", "diverged (documented)"
    except Hang as exc:
        return "failure", f"hang: {exc}"
    except Exception as exc:  # noqa: BLE001 - a raw error is what this looks for
        return "failure", f"{type(exc).__name__}: {str(exc)[:200]}"
    if isinstance(value, float) and math.isnan(value):
        return "failure", "a silent NaN"
    return "correct", type(value).__name__


def bounded_property(examples: int):
    """The property tests' hypothesis settings: ``examples`` drawn in a fixed order (CI stays
    within its time and a failure repeats), no deadline (a drive may compile), no health
    checks (hostile values are slow and filtered on purpose)."""
    import hypothesis

    return hypothesis.settings(
        max_examples=examples,
        deadline=None,
        derandomize=True,
        suppress_health_check=list(hypothesis.HealthCheck),
    )
