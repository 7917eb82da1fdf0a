"""What the registries of compiled plug-ins share (the speed estimators,
:mod:`imdrive.kernels.estimators.registry`, and the R2 laws,
:mod:`imdrive.kernels.r2_law_registry`): record dtypes made unique per plug-in, and the
indexes by name and by record type that numba's generic entry points resolve through.

A plug-in's records carry a tag field (:func:`tagged`) whose name holds the plug-in's name
and, for a module outside the package, a hash of the module's name and text
(:func:`source_tag`): the compiled loop inlines the plug-in, so an edited module must be a new
record type, compiled afresh, never taken stale from the cache.
"""

from __future__ import annotations

import hashlib
import inspect
import re
from pathlib import Path

import numpy as np

_PACKAGE = Path(__file__).resolve().parents[1]


def source_tag(func) -> str:
    """A short hash of the module defining ``func``: its name and its file's text ('' for the
    package's own files). The name counts too: a cached loop refers to the plug-in's module
    by name, so the same text loaded under another name must not find it."""
    py = getattr(func, "py_func", func)
    try:
        path = Path(inspect.getsourcefile(py) or "")
        text = path.read_bytes()
    except (TypeError, OSError):
        return "nosource"
    if _PACKAGE in path.resolve().parents:
        return ""  # the package's cache folder already follows its sources
    return hashlib.sha256(py.__module__.encode() + b"\0" + text).hexdigest()[:12]


def tagged(dtype: np.dtype, name: str, tag: str) -> np.dtype:
    """``dtype`` with the tag field ``est_<name>[_<tag>]`` (uint8) appended."""
    ident = re.sub(r"\W", "_", name)
    fields = [(n, dtype.fields[n][0]) for n in dtype.names]
    fields.append((f"est_{ident}_{tag}" if tag else f"est_{ident}", np.uint8))
    return np.dtype(fields)


class Registry:
    """Registered plug-ins by name and by each of their record dtypes (``params``,
    ``state``); registering a name again replaces the entry and its records (a re-imported
    user module)."""

    def __init__(self, what: str):
        self.what = what
        self.by_name: dict = {}
        self.by_record: dict = {}

    def add(self, kernel):
        """Register ``kernel`` (an object with ``name``, ``params`` and ``state``); return it."""
        old = self.by_name.pop(kernel.name, None)
        if old is not None:
            self.by_record.pop(old.state, None)
            self.by_record.pop(old.params, None)
        self.by_name[kernel.name] = kernel
        self.by_record[kernel.state] = kernel
        self.by_record[kernel.params] = kernel
        return kernel

    def __getitem__(self, name: str):
        try:
            return self.by_name[name]
        except KeyError:
            known = sorted(self.by_name)
            raise KeyError(f"no {self.what} {name!r} is registered (known: {known})") from None

    def names(self) -> tuple[str, ...]:
        """Every registered name, in registration order."""
        return tuple(self.by_name)
