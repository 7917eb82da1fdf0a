"""The files ``imdrive run`` writes besides summary.json, as a registry: one module per format.

Each module of this package defines ``FORMAT``, an :class:`OutputFormat` naming the format,
the file name(s) it writes, its writer and the ``[output]`` key that switches it on
(:class:`~imdrive.config.output.OutputSettings`). :meth:`SimulationResult.save
<imdrive.run.result.SimulationResult.save>` writes every format whose key is on,
:func:`~imdrive.run.files.is_result_folder` recognises their files and ``docs/outputs.md``
lists them (:mod:`imdrive.run.outputs`), all from :func:`output_formats`. A new format is a new
module here (with its key in ``OutputSettings``); nothing else is registered by hand.
"""

from __future__ import annotations

import functools
import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass
from fnmatch import fnmatchcase
from pathlib import Path

__all__ = ["OutputFormat", "formats_wanted", "output_formats"]


@dataclass(frozen=True)
class OutputFormat:
    """One kind of file of a result folder.

    Attributes
    ----------
    name : str
        Short name (``"csv"``, ``"parquet"``, ...).
    key : str
        The field of :class:`~imdrive.config.output.OutputSettings` (``[output] KEY``) that
        switches it on.
    files : tuple of str
        The file names it writes, or shell patterns (``"*.png"``) when they vary.
    write : callable
        ``write(result, folder)``: writes the files of ``result`` into ``folder``.
    description : str
        What the files hold, for ``docs/outputs.md``.
    order : int
        Position in the writing order and in the docs (smaller first).
    """

    name: str
    key: str
    files: tuple[str, ...]
    write: Callable[[object, Path], None]
    description: str
    order: int

    def owns(self, file_name: str) -> bool:
        """Whether ``file_name`` is one of this format's files.

        Parameters
        ----------
        file_name : str
            A file name (no folder).

        Returns
        -------
        bool
            True if it equals or matches one of :attr:`files`.
        """
        return any(fnmatchcase(file_name, pattern) for pattern in self.files)


@functools.cache
def output_formats() -> tuple[OutputFormat, ...]:
    """Every registered format: the ``FORMAT`` of each module of this package, in ``order``.

    Returns
    -------
    tuple of OutputFormat
        The formats, sorted by their ``order``.
    """
    found = []
    for info in pkgutil.iter_modules(__path__, f"{__name__}."):
        module = importlib.import_module(info.name)
        found.append(module.FORMAT)
    return tuple(sorted(found, key=lambda f: (f.order, f.name)))


def formats_wanted(names) -> dict[str, bool]:
    """``[output]`` key -> on, with exactly the formats ``names`` on (``res.save(formats=)``,
    ``imdrive run --format``).

    Parameters
    ----------
    names : iterable of str
        Format names (:func:`imdrive.run.formats.output_formats`).

    Returns
    -------
    dict
        The ``[output]`` key of every format -> whether it is written.

    Raises
    ------
    ConfigError
        An unknown name (the known ones listed).
    """
    from imdrive.errors import ConfigError

    if isinstance(names, str):
        names = [names]
    known = {f.name: f.key for f in output_formats()}
    names = list(names)
    for n in names:
        if n not in known:
            raise ConfigError("formats", f"no output format {n!r}; known: {', '.join(known)}")
    return {key: name in names for name, key in known.items()}
