"""Where the compiled kernels are cached on disk.

numba invalidates a cached function only when *its own* source file changes, not when a kernel
it calls from another module does. The kernels here call each other across modules (the engine
inlines the machine, inverter, controller, MRAS and compensator), so the cache lives in a folder
named after a hash of every source file of the package: any change to any of them starts a
fresh cache, and an unchanged package reuses it across processes.

The folder is under ``$IMDRIVE_CACHE_DIR`` if set, else under ``$NUMBA_CACHE_DIR/imdrive`` if
that is set, else under ``$XDG_CACHE_HOME/imdrive`` (default ``~/.cache/imdrive``); it falls back
to the system temporary folder if that is not writable.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import tempfile
from pathlib import Path

import numba

_PKG = Path(__file__).resolve().parent


def source_hash(root: Path = _PKG) -> str:
    """Short hash of every ``.py`` file under ``root`` (names and contents) and numba's version."""
    h = hashlib.sha256()
    for p in sorted(root.rglob("*.py")):
        h.update(str(p.relative_to(root)).encode())
        h.update(p.read_bytes())
    h.update(numba.__version__.encode())
    return h.hexdigest()[:16]


def cache_dir() -> Path:
    base = os.environ.get("IMDRIVE_CACHE_DIR")
    if base:
        root = Path(base)
    elif os.environ.get("NUMBA_CACHE_DIR"):
        root = Path(os.environ["NUMBA_CACHE_DIR"]) / "imdrive"
    else:
        xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        root = Path(xdg) / "imdrive"
    path = root / f"kernels-{source_hash()}"
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / ".write-test"
        probe.write_text("")
        probe.unlink()
    except OSError:
        path = Path(tempfile.gettempdir()) / "imdrive" / f"kernels-{source_hash()}"
        path.mkdir(parents=True, exist_ok=True)
    return path


@contextlib.contextmanager
def kernel_cache():
    """Decorate the kernels defined inside this block with the package's cache folder."""
    old = numba.config.CACHE_DIR
    numba.config.CACHE_DIR = str(cache_dir())
    try:
        yield
    finally:
        numba.config.CACHE_DIR = old
