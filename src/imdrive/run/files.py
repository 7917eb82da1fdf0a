"""A result folder: summary.json as strict JSON, the files a result may hold, and the check
that refuses to replace a folder that is not a result."""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path

from imdrive.run.formats import output_formats

#: The file names :meth:`~imdrive.run.result.SimulationResult.save` may write (summary.json and
#: every registered format's fixed names; the PNG figures' names vary, see
#: :func:`is_result_folder`)
RESULT_FILES = ("summary.json",) + tuple(
    name for f in output_formats() for name in f.files if not any(c in name for c in "*?[")
)

NULL_NOTE = (
    "null stands for a value that is not a finite number (NaN or infinite: a diverged run's "
    "last states, a metric with no samples); JSON has no NaN or Infinity"
)


def _finite_or_null(obj):
    """``obj`` with every non-finite float replaced by None (recursively); and whether any was."""
    if isinstance(obj, float):
        return (obj, False) if math.isfinite(obj) else (None, True)
    if isinstance(obj, dict):
        out, any_null = {}, False
        for k, v in obj.items():
            out[k], n = _finite_or_null(v)
            any_null |= n
        return out, any_null
    if isinstance(obj, list | tuple):
        items = [_finite_or_null(v) for v in obj]
        return [v for v, _ in items], any(n for _, n in items)
    return obj, False


def summary_json(summary: dict) -> str:
    """``summary`` as strict JSON: NaN and infinities written as null, with a ``"note"`` saying
    so when there are any (most JSON parsers refuse bare ``NaN``/``Infinity``)."""
    clean, any_null = _finite_or_null(summary)
    if any_null:
        clean["note"] = NULL_NOTE
    return json.dumps(clean, indent=2, allow_nan=False) + "\n"


def is_result_folder(folder) -> bool:
    """Whether ``folder`` is missing, empty, or holds only what
    :meth:`~imdrive.run.result.SimulationResult.save` writes (``summary.json``, the files of
    every output format of :mod:`imdrive.run.formats`, staging leftovers)."""
    from imdrive._io import LOCK_NAME, is_partial

    folder = Path(folder)
    if not folder.exists():
        return True
    if not folder.is_dir():
        return False
    for p in folder.iterdir():
        n = p.name
        if is_partial(n) or n == LOCK_NAME:
            continue
        if p.is_file() and not p.is_symlink() and owns_result_file(n):
            continue
        return False
    return True


def owns_result_file(name: str) -> bool:
    """Whether a file of that name is one :meth:`~imdrive.run.result.SimulationResult.save`
    writes (``summary.json``, a file of a registered output format)."""
    return name == "summary.json" or any(f.owns(name) for f in output_formats())


def check_result_folder(folder, force: bool = False) -> None:
    """Refuse (:class:`~imdrive.errors.ConfigError` on ``--out``) to replace a folder that is
    not an imdrive result, unless ``force``; and a path no result may be written at (the
    current folder, under a file): the rule of every command
    (:func:`imdrive._io.output_folder_problem`).
    """
    import os

    from imdrive._io import output_folder_problem
    from imdrive.errors import ConfigError

    if not isinstance(folder, str | os.PathLike):
        raise ConfigError("out_dir", f"must be a folder path, got {type(folder).__name__}")
    problem = output_folder_problem(folder, owns_result_file, force, "an imdrive result")
    if problem is not None:
        raise ConfigError("--out", problem)


def package_versions() -> dict[str, str]:
    """The versions a result's ``summary.json`` records: imdrive, Python, numpy, scipy, numba
    (a copy of :func:`_versions`, read once per process)."""
    return dict(_versions())


@functools.cache
def _versions() -> dict[str, str]:
    # reading the packages' metadata takes about 8 ms, on every save until it was kept
    import platform
    from importlib.metadata import version

    import imdrive

    return {
        "imdrive": imdrive.__version__,
        "python": platform.python_version(),
        "numpy": version("numpy"),
        "scipy": version("scipy"),
        "numba": version("numba"),
    }
