"""Where the compiled kernels are cached on disk, and when they are compiled again.

numba invalidates a cached function only when *its own* source file changes, not when a kernel
it calls from another module does: the engine inlines the machine, inverter, controller,
estimators and compensator, all from other files. So each kernel module caches into a folder
of its own, ``<module>-<key>``, whose key is a hash of

* the source of the module and of every kernel module it imports, transitively (read from the
  ``import`` statements, not by importing); a module that sets ``_CACHE_FOLLOWS_IMPORTERS =
  True`` (the estimator registry, whose generic entry points compile the step of whichever
  estimator registered with it) also depends on every module that imports it;
* the versions of Python, numba, llvmlite and numpy, and the processor architecture.

An edit outside ``kernels/`` (``config/``, ``run/``, the CLI, ...) therefore compiles nothing
again; an edit of ``kernels/linearise.py`` compiles only the stability kernels, not the drive.
The key is of contents, not of paths or times: a reinstall, a fresh clone or a copy of the same
code reuses the cache.

Every kernel file's cache lives in that folder, the estimator registry's generic entry points
(compiled later, while the engine compiles) included: a numba cache locator of our own
(:class:`_KernelLocator`) claims every function defined under ``kernels/``, so nothing is ever
written into the source tree or site-packages. For each module the most recently used
:data:`KEEP` folders are kept, and so is every folder used within :data:`MAX_AGE_DAYS` up to
:data:`MAX_RECENT` of them (a developer with several branches or worktrees switches between
their kernels without compiling each again); older ones are removed, with the single-hash
``kernels-<hash>`` folders of imdrive 0.2 and before.

The folders are under ``$IMDRIVE_CACHE_DIR`` if set, else under ``$NUMBA_CACHE_DIR/imdrive`` if
that is set, else under ``$XDG_CACHE_HOME/imdrive`` (default ``~/.cache/imdrive``); the system
temporary folder if that is not writable.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import itertools
import json
import os
import platform
import shutil
import sys
import tempfile
import time
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

_PKG = Path(__file__).resolve().parent
KERNELS = _PKG / "kernels"
#: Folders kept per kernel module (the most recently used): the current code's, and two earlier
#: versions a developer may switch back to (another branch, an undone edit).
KEEP = 3
#: A folder used within this many days is kept beyond :data:`KEEP` (every version of a module in
#: use on the machine), up to :data:`MAX_RECENT` of them per module. With KEEP alone, four
#: worktrees of the project evicted each other's kernels at every switch: 2-3 min of
#: compilation each time (a module's folders are 0.1-20 MB: the whole cache of this machine's
#: four branches was 55 MB).
MAX_AGE_DAYS = 7.0
MAX_RECENT = 10
_MARK = "_CACHE_FOLLOWS_IMPORTERS"


def _versions() -> bytes:
    parts = [sys.implementation.cache_tag or "", platform.machine()]
    for dist in ("numba", "llvmlite", "numpy"):
        try:
            parts.append(f"{dist}={version(dist)}")
        except PackageNotFoundError:  # a source checkout of one of them: its module's version
            parts.append(f"{dist}={getattr(__import__(dist), '__version__', '?')}")
    return "\0".join(parts).encode()


def _module_name(path: Path, root: Path) -> str:
    rel = path.relative_to(root.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return "imdrive." + ".".join(parts)


def _imports(tree: ast.Module, name: str, is_package: bool, known: set[str]) -> set[str]:
    """The kernel modules a module (``name``, parsed as ``tree``) imports, from its import
    statements."""
    package = name if is_package else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: from the package, up level - 1
                anchor = package.split(".")
                anchor = anchor[: len(anchor) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            found.add(base)
            found.update(f"{base}.{a.name}" for a in node.names)  # `from pkg import module`
    return {m for m in found if m in known and m != name}


def _marked(tree: ast.Module) -> bool:
    return any(
        isinstance(n, ast.Assign) and any(getattr(t, "id", None) == _MARK for t in n.targets)
        for n in tree.body
    )


@functools.cache
def module_keys(root: Path = KERNELS) -> dict[str, str]:
    """The cache key of every module under ``root`` (``imdrive.kernels`` by default).

    The dependency analysis parses every kernel module (0.1-0.3 s); its result is kept in the
    cache root under a hash of all the sources, so a process that starts with unchanged kernels
    only reads and hashes them (a few ms).

    Returns
    -------
    dict of str to str
        Module name -> 16 hex digits: a hash of the module's source, of the sources of the
        kernel modules it depends on (module docstring) and of the tool versions.
    """
    files = {_module_name(p, root): p for p in sorted(root.rglob("*.py"))}
    text = {m: p.read_bytes() for m, p in files.items()}
    whole = hashlib.sha256(_versions())
    for m, t in text.items():
        whole.update(m.encode() + b"\0" + hashlib.sha256(t).digest())
    memo = None
    with contextlib.suppress(OSError, ValueError):  # no memo yet, or a damaged one
        memo = cache_root() / f"module-keys-{whole.hexdigest()[:16]}.json"
        keys = json.loads(memo.read_text())
        if isinstance(keys, dict) and set(keys) == set(files):
            return keys
    keys = _compute_keys(files, text)
    if memo is not None:
        with contextlib.suppress(OSError):
            tmp = memo.with_name(f"{memo.name}.{os.getpid()}.tmp")
            tmp.write_text(json.dumps(keys))
            os.replace(tmp, memo)
    return keys


def _compute_keys(files: dict[str, Path], text: dict[str, bytes]) -> dict[str, str]:
    trees = {m: ast.parse(text[m], filename=str(p)) for m, p in files.items()}
    known = set(files)
    deps = {m: _imports(trees[m], m, p.name == "__init__.py", known) for m, p in files.items()}
    for m in files:
        if _marked(trees[m]):
            deps[m] |= {other for other, d in deps.items() if m in d}
    for m in files:  # a module's parent packages run first: their files count too
        parts = m.split(".")
        deps[m] |= {".".join(parts[:i]) for i in range(2, len(parts))} & known
    versions = _versions()
    source = {m: hashlib.sha256(t).digest() for m, t in text.items()}
    keys = {}
    for m in files:
        seen, todo = {m}, [m]
        while todo:
            for d in deps[todo.pop()] - seen:
                seen.add(d)
                todo.append(d)
        h = hashlib.sha256(versions)
        for d in sorted(seen):
            h.update(d.encode() + b"\0" + source[d])
        keys[m] = h.hexdigest()[:16]
    return keys


def cache_root() -> Path:
    """The folder holding every kernel module's cache folder (created if missing)."""
    base = os.environ.get("IMDRIVE_CACHE_DIR")
    if base:
        root = Path(base)
    elif os.environ.get("NUMBA_CACHE_DIR"):
        root = Path(os.environ["NUMBA_CACHE_DIR"]) / "imdrive"
    else:
        xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        root = Path(xdg) / "imdrive"
    root = _writable(root)
    root.mkdir(parents=True, exist_ok=True)  # removed since it was probed (a test's folder)
    return root


@functools.cache
def _writable(root: Path) -> Path:
    """``root`` if a file can be created in it, else the system temporary folder's ``imdrive``.

    Probed once per process and folder: every kernel function asks for its folder while it is
    decorated (209 of them), and a probe creates and removes a file.
    """
    try:
        root.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=root):
            pass
    except OSError:
        root = Path(tempfile.gettempdir()) / "imdrive"
    return root


#: Kept for callers of imdrive 0.2: the folder every kernel cache lives under.
cache_dir = cache_root


def module_folder(module: str, root: Path | None = None) -> Path:
    """The cache folder of kernel module ``module`` (``imdrive.kernels.engine``, ...)."""
    return (root or cache_root()) / f"{module}-{module_keys()[module]}"


def prune(
    root: Path | None = None,
    keep: int = KEEP,
    max_age_days: float = MAX_AGE_DAYS,
    max_recent: int = MAX_RECENT,
    now: float | None = None,
) -> list[Path]:
    """Remove the folders of each kernel module but the ``keep`` most recently used and those
    used within ``max_age_days`` (at most ``max_recent`` in all), and the single-hash
    ``kernels-*`` folders of imdrive 0.2; return what was removed."""
    root = root or cache_root()
    groups: dict[str, list[Path]] = {}
    removed = []
    for p in root.iterdir() if root.is_dir() else ():
        if p.name.startswith(("module-keys-", "warm-", "plotly-")) and p.suffix in (
            ".json",
            ".done",
            ".b64",
        ):  # memo files, warm-up stamps, the report's compressed plotly.js
            groups.setdefault(p.name.split("-")[0], []).append(p)
            continue
        if not p.is_dir():
            continue
        if p.name.startswith("kernels-"):
            removed.append(p)
        elif p.name.startswith("imdrive.kernels") and "-" in p.name:
            groups.setdefault(p.name.rpartition("-")[0], []).append(p)
    since = (time.time() if now is None else now) - 86400.0 * max_age_days
    for folders in groups.values():
        folders.sort(key=lambda p: p.stat().st_mtime, reverse=True)
        for i, p in enumerate(folders):
            if i >= keep and (i >= max(max_recent, keep) or p.stat().st_mtime < since):
                removed.append(p)
    for p in removed:  # another process may be reading an old one: it then compiles afresh
        if p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)
    return removed


@functools.cache
def _claimed(py_file: str) -> str | None:
    """The kernel module defined by ``py_file``, if it is one of this package's."""
    try:
        path = Path(py_file).resolve()
        if not path.is_relative_to(KERNELS):
            return None
        return _module_name(path, KERNELS)
    except (OSError, ValueError):
        return None


@functools.cache
def _used(folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    os.utime(folder)  # recency for prune()
    return folder


def _locator_class():
    from numba.core import caching

    class _KernelLocator(caching._CacheLocator):
        """numba cache locator for the functions of ``imdrive.kernels``: the module's folder,
        stamped with its key (a cache entry is stale exactly when the key changes)."""

        def __init__(self, py_func, py_file: str, module: str):
            self._py_file = py_file  # numba names it in its "cannot cache" warning
            self._lineno = py_func.__code__.co_firstlineno
            self._key = module_keys()[module]
            self._path = _used(module_folder(module))

        def get_cache_path(self):
            return str(self._path)

        def get_source_stamp(self):
            return self._key

        def get_disambiguator(self):
            return str(self._lineno)

        @classmethod
        def from_function(cls, py_func, py_file):
            module = _claimed(py_file)
            if module is None or module not in module_keys():
                return None
            try:
                return cls(py_func, py_file, module)
            except OSError:  # not writable: numba's own locators decide
                return None

    return _KernelLocator


@functools.cache
def install() -> bool:
    """Put the kernel locator first in numba's list (once per process); prune old folders.

    Returns
    -------
    bool
        False if this numba has no locator list (then :func:`kernel_cache` points numba's
        ``CACHE_DIR`` at the cache root while the kernels are decorated, as before).
    """
    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    locators = getattr(impl, "_locator_classes", None)
    if not isinstance(locators, list):
        return False
    locators.insert(0, _locator_class())
    _lock_index_saves(caching)
    with contextlib.suppress(OSError):
        prune()
    return True


@contextlib.contextmanager
def _locked(path: Path):
    """An exclusive lock on the file ``path`` (created), across processes; none where the
    system offers neither ``fcntl`` nor ``msvcrt``."""
    with open(path, "a+b") as f:
        try:
            import fcntl

            fcntl.flock(f, fcntl.LOCK_EX)
        except ImportError:  # Windows
            import msvcrt

            f.seek(0)
            msvcrt.locking(f.fileno(), msvcrt.LK_LOCK, 1)
        yield


def _lock_index_saves(caching) -> None:
    """Make numba's cache index safe for processes that save to it at once (ours only).

    numba adds an entry by reading the index, choosing the first free data file number,
    writing the index and then the data, with no lock: two processes compiling new
    specialisations of one kernel at the same time (two terminals, a sweep's workers, the
    test suite's two workers) lose entries and, worse, leave an entry naming the other's
    data file, whose machine code is then loaded for the wrong signature. Measured with two
    processes saving 40 entries each to one index at once: 48-52 of 80 kept, 6-8 of them
    pointing at the other's code (``benchmarks/README.md``). Under the package's cache root
    the whole read-choose-write now runs under a file lock, data before index, so an entry is
    never lost and never names data that is not its own.
    """
    cls = caching.IndexDataCacheFile
    if getattr(cls.save, "_imdrive_locked", False):
        return
    unlocked = cls.save

    def save(self, key, data):
        folder = Path(self._cache_path)
        if not folder.resolve().is_relative_to(cache_root().resolve()):
            return unlocked(self, key, data)
        with _locked(folder / f"{self._index_name}.lock"):
            overloads = self._load_index()
            name = overloads.get(key)
            if name is None:
                taken = set(overloads.values())
                name = next(
                    n
                    for n in map(self._data_name, itertools.count(1))
                    if n not in taken and not (folder / n).exists()
                )
                overloads[key] = name
            self._save_data(name, data)
            self._save_index(overloads)

    save._imdrive_locked = True
    cls.save = save


@contextlib.contextmanager
def kernel_cache():
    """Decorate the kernels defined inside this block with the package's cache folders."""
    if install():
        yield
        return
    import numba

    old = numba.config.CACHE_DIR
    numba.config.CACHE_DIR = str(cache_root())
    try:
        yield
    finally:
        numba.config.CACHE_DIR = old
