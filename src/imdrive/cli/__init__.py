"""The ``imdrive`` command.

Exit codes
----------
0 (``EXIT_OK``)
    Done.
1 (``EXIT_DIVERGED``)
    A physical outcome: the run diverged. Its partial results are written, marked
    ``"diverged": true`` in summary.json.
2 (``EXIT_BAD_INPUT``)
    Bad input (an unknown preset, key or type, a value that breaks a rule, a derived quantity
    that overflows, an unsafe name, a sweep above ``--max-runs``, an ``--out`` folder that
    holds other files, a path the user gave that the system cannot use: too long, through a
    file, missing, a special file where a file is read): one line
    ``imdrive: error: field: rule`` on stderr, nothing written.
3 (``EXIT_LOST_CONTROL``)
    A physical outcome: the run completed but lost control of the speed (it stayed more than
    ``simulation.lost_control_rpm`` from its reference for ``simulation.lost_control_s``: a
    runaway, a sustained limit cycle). Results written, marked ``"lost_control": true``.
4 (``EXIT_ENVIRONMENT``)
    The environment failed: an I/O error, a full disk, a permission, memory, a dask cluster
    that lost its workers or scheduler, a sweep store locked by another process. One line
    naming the cause, no traceback; what was already written stays and looks incomplete (no
    summary.json, a sweep manifest without ``"complete": true``; ``--resume`` continues a
    sweep).
5 (``EXIT_INTERNAL``)
    An unexpected error (a bug): one line; set ``IMDRIVE_DEBUG=1`` for the traceback.
6 (``EXIT_NOT_IDENTIFIED``)
    ``imdrive commission``: a test of the identification run did not converge (one line
    naming the test and why); no ``identified.toml`` is written.
130
    Interrupted (Ctrl-C).
141 (``EXIT_CLOSED_PIPE``)
    The standard output's reader closed it (``imdrive presets | head -2``): the command stops
    quietly, with no message, and exits as a process that the shell saw killed by SIGPIPE
    (128 + 13), like ``yes | head``. 141 rather than 0: a run cut short this way is not done.

A sweep records its diverging runs (``diverged``, ``status``), those that lost control
(``lost_control``, ``lost_control_at_s``) and the runs that could not be built (``status`` -1,
``error``) in its table and exits 0.

Each command group is one module of this package with an ``add_parser(sub)`` that registers
its sub-command (:data:`COMMANDS`); a new command is a new module listed there.
"""

from __future__ import annotations

import argparse
import functools
import os
import sys
import time
import warnings

from imdrive.cli import (
    bench,
    commission,
    compare,
    info,
    machine,
    paper,
    replay,
    run,
    stability,
    sweep,
    warmup,
)
from imdrive.cli._common import (
    EXIT_BAD_INPUT,
    EXIT_CLOSED_PIPE,
    EXIT_DIVERGED,
    EXIT_ENVIRONMENT,
    EXIT_INTERNAL,
    EXIT_LOST_CONTROL,
    EXIT_OK,
    NAME_MAX_BYTES,
    OUT_ROOT,
    PATH_MAX_BYTES,
    _examples,
    _out_path,
    _Parser,
)
from imdrive.cli.info import _cmd_fuzzy_table, _cmd_presets, _cmd_show
from imdrive.cli.run import _cmd_run, _run_folder_name
from imdrive.cli.stability import _cmd_stability, _parse_range, _parse_ratios
from imdrive.errors import ConfigError, ConfigWarning, EnvironmentFailure, describe_os_error

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_CLOSED_PIPE",
    "EXIT_DIVERGED",
    "EXIT_ENVIRONMENT",
    "EXIT_INTERNAL",
    "EXIT_LOST_CONTROL",
    "EXIT_OK",
    "NAME_MAX_BYTES",
    "OUT_ROOT",
    "PATH_MAX_BYTES",
    "_Parser",
    "_cmd_fuzzy_table",
    "_cmd_presets",
    "_cmd_run",
    "_cmd_show",
    "_cmd_stability",
    "_examples",
    "_out_path",
    "_parse_range",
    "_parse_ratios",
    "_run_folder_name",
    "build_parser",
    "main",
]

#: the exit-code table of ``imdrive --help`` (the module docstring says more)
EXIT_CODES_HELP = """exit codes:
  0    done
  1    the run diverged (partial results written, "diverged": true in summary.json)
  2    bad input: one line 'imdrive: error: field: rule', nothing written
  3    the run lost control of the speed (results written, "lost_control": true)
  4    the environment failed (I/O, disk full, permission, memory, dask, a locked store)
  5    internal error (a bug); IMDRIVE_DEBUG=1 shows the traceback
  6    imdrive commission: a test did not converge (it says which and why), nothing written
  130  interrupted (Ctrl-C)
  141  stdout's reader closed it (| head): stopped quietly, as on SIGPIPE
a sweep records its diverged and lost runs in its table and exits 0."""

#: the command groups, in the order ``imdrive --help`` lists them
COMMANDS = (run, replay, compare, info, paper, sweep, stability, bench, machine, commission, warmup)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="imdrive",
        description="Simulate sensorless induction-motor drives.",
        epilog=_examples(
            "imdrive presets",
            "imdrive run sensorless",
            "imdrive show sensorless > my.toml; imdrive run my.toml",
            "imdrive sweep detuning-map",
            "imdrive compare out/sensorless out/sensorless-realistic --out out/cmp",
            "imdrive <command> --help",
        )
        + "\n\n"
        + EXIT_CODES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--version", action="version", version=_version())
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for module in COMMANDS:
        module.add_parser(sub)
    return p


@functools.cache
def _parser() -> argparse.ArgumentParser:
    """:func:`build_parser`'s parser, built once per process: it holds nothing of a parse, and
    building its hundred arguments (argparse looks up a translation for each help text) took
    two thirds of an in-process ``main()`` that stops at bad input (the hostile-input tests
    call it 2,700 times)."""
    return build_parser()


def _version() -> str:
    from imdrive import __version__

    return f"imdrive {__version__}"


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """A :class:`~imdrive.errors.ConfigWarning` as one line ``imdrive: warning: field: rule``;
    other warnings as Python prints them."""
    if issubclass(category, ConfigWarning):
        print(f"imdrive: warning: {message}", file=sys.stderr)
    else:
        print(warnings.formatwarning(message, category, filename, lineno, line), file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Run the ``imdrive`` command; returns its exit code (the module docstring lists them)."""
    try:
        try:
            code = _main(argv)
        finally:
            # flushed here, so that a closed pipe shows now and not in the interpreter's exit
            # ("Exception ignored ... BrokenPipeError"), also after --help's SystemExit
            sys.stdout.flush()
    except BrokenPipeError:
        return _closed_pipe()
    return code


def _closed_pipe() -> int:
    """The reader of stdout went away: point stdout at /dev/null, so that nothing else (the
    interpreter's last flush) fails on it, and exit quietly (:data:`EXIT_CLOSED_PIPE`)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # a stdout without a file descriptor (captured, replaced)
        pass
    return EXIT_CLOSED_PIPE


def _main(argv: list[str] | None) -> int:
    args = _parser().parse_args(argv)
    args.t0 = time.perf_counter()
    if not getattr(args, "quiet", False):
        from imdrive import _compiling

        _compiling.enable()
    try:
        with warnings.catch_warnings(), _plugin_rule(args):
            warnings.showwarning = _show_warning
            return args.func(args)
    except ConfigError as exc:
        return _fail(f"{exc}{_did_you_mean(exc, args)}", EXIT_BAD_INPUT)
    except EnvironmentFailure as exc:
        return _fail(exc.cause, EXIT_ENVIRONMENT)
    except BrokenPipeError:
        raise  # stdout's reader went away: main() ends quietly
    except MemoryError:
        return _fail("out of memory (a smaller sweep, chunk or log_every?)", EXIT_ENVIRONMENT)
    except OSError as exc:
        from imdrive.config.user_files import users_path_error

        mine = users_path_error(exc, sys.argv[1:] if argv is None else argv)
        if mine is not None:  # the form of a path the user gave: theirs to fix
            return _fail(mine, EXIT_BAD_INPUT)
        return _fail(describe_os_error(exc), EXIT_ENVIRONMENT)
    except KeyboardInterrupt:
        print("imdrive: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:
        if os.environ.get("IMDRIVE_DEBUG"):
            raise
        msg = str(exc).splitlines()[0][:300] if str(exc) else ""
        return _fail(
            f"internal error ({type(exc).__name__}: {msg}); set IMDRIVE_DEBUG=1 for the traceback",
            EXIT_INTERNAL,
        )


#: the commands that only look at files: they never import a plug-in module
LOOKING_COMMANDS = ("show", "compare")


def _plugin_rule(args):
    """The plug-in rule of this invocation (:mod:`imdrive.config.plugins`): a command that
    only looks at files (``show``, ``compare``, ``sweep --dry-run``) imports no module; one
    that runs a drive imports them with ``--allow-plugins`` (or ``IMDRIVE_ALLOW_PLUGINS=1``)."""
    import contextlib

    look = args.command in LOOKING_COMMANDS or (
        args.command == "sweep" and getattr(args, "dry_run", False)
    )
    if look:
        from imdrive.config.plugins import looking

        return looking()
    if getattr(args, "allow_plugins", False):
        from imdrive.config.plugins import allowing_plugins

        return allowing_plugins(True)
    return contextlib.nullcontext()


def _did_you_mean(exc: ConfigError, args) -> str:
    """``"; did you mean 'X'?"`` for a mistyped key, preset or sweep name (difflib), else ``""``.

    Appended by the command line only: the library's messages stay as they are.
    """
    import difflib

    rule = exc.rule
    given, names, cutoff = None, [], 0.6
    if rule.startswith(("unknown key", "no such setting")):
        from imdrive.config.schema import setting_paths

        paths = setting_paths()
        given = exc.field
        names = sorted({".".join(p) for p in paths} | {p[0] for p in paths})
        cutoff = 0.75
    elif exc.field in ("preset", "scenario") and (
        "unknown preset" in rule or "neither a preset" in rule
    ):
        from imdrive.config.presets import preset_names

        given = getattr(args, "scenario", None) or getattr(args, "preset", None)
        names = preset_names()
    elif exc.field == "sweep" and "neither a built-in sweep" in rule:
        from imdrive.sweep import sweep_names

        given, names = getattr(args, "sweep", None), sweep_names()
    if not given or not names:
        return ""
    match = difflib.get_close_matches(str(given), names, n=1, cutoff=cutoff)
    return f"; did you mean {match[0]!r}?" if match and match[0] != given else ""


def _fail(message: str, code: int) -> int:
    """Print one line on stderr and return the exit code."""
    print(f"imdrive: error: {message}", file=sys.stderr)
    return code
