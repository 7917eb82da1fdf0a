"""``imdrive ARGS`` through ``main`` in the test's process, reported as a subprocess would report
it (``from data.inprocess import imdrive_here``): the bad-input tests run most of their cases
this way, one of each kind through ``python -m imdrive`` (an interpreter's start and imports
are 1.5-4 s on a loaded 2-core machine)."""

from __future__ import annotations

import os
import subprocess
import warnings
from contextlib import redirect_stderr, redirect_stdout
from io import StringIO
from pathlib import Path


def imdrive_here(*args, cwd: Path) -> subprocess.CompletedProcess:
    """``imdrive ARGS`` run by ``main`` in this process, from ``cwd``: the exit code, stdout and
    stderr, each warning shown as a line of stderr (with Python's default filters, as the
    command's interpreter shows them). A traceback is the exception itself."""
    from imdrive.cli import main

    out, err, here = StringIO(), StringIO(), Path.cwd()
    with warnings.catch_warnings(record=True) as caught:
        warnings.resetwarnings()  # Python's defaults, not pytest's
        for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning):
            warnings.simplefilter("ignore", category)
        warnings.simplefilter("ignore", ResourceWarning)
        os.chdir(cwd)
        try:
            with redirect_stdout(out), redirect_stderr(err):
                try:
                    rc = main([str(a) for a in args])
                except SystemExit as exc:  # argparse's usage errors
                    rc = exc.code if isinstance(exc.code, int) else 1
        finally:
            os.chdir(here)
    shown = "".join(
        f"{w.filename}:{w.lineno}: {w.category.__name__}: {w.message}\n" for w in caught
    )
    return subprocess.CompletedProcess(args, rc, out.getvalue(), err.getvalue() + shown)
