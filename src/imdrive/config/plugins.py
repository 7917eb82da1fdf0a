"""Estimators from outside the package: the ``[plugins]`` section and the import of modules.

A scenario that uses an estimator defined in the user's own module names that module in
``[plugins] modules`` (a dotted module name on ``sys.path``, or the path of a ``.py`` file);
reading the scenario imports it first, so the estimator registers itself (its settings class
with :func:`imdrive.config.estimators.estimator_settings`, its compiled half with
:func:`imdrive.kernels.estimators.registry.register_kernel`) before ``control.speed_feedback``
is checked. The estimator's settings are the table ``[plugins.settings.NAME]``. A scenario
built in Python after the module was imported gets the module added to ``modules``
automatically, so the scenario file it writes (``summary.json``), a sweep's worker process
and a rerun find the estimator again.

Importing a module runs its code, so a plug-in is **opt-in**: a module listed in a scenario
(a TOML file, a ``summary.json``, a sweep file, a ``--set``) is imported only when the user
allows it for this invocation: ``--allow-plugins`` on the command line,
``IMDRIVE_ALLOW_PLUGINS=1`` in the environment, or ``allow_plugins=True`` in the API
(:func:`allowing_plugins`). Without it, reading the scenario raises a :class:`ConfigError`
naming the module, and no code of it runs. A module already imported in this process (by the
user's own code, or allowed earlier) runs nothing new and needs no permission. Looking at a
file (``imdrive show``, ``sweep --dry-run``, ``compare``: :func:`looking`) never imports: the
module is listed, the estimator's own settings are left unchecked. A relative module path in
a file is resolved against that file's folder (:func:`resolve_plugin_paths`); each module's
sha256 is recorded (:func:`module_hashes`) so a rerun can say that a module changed.
"""

from __future__ import annotations

import contextlib
import contextvars
import hashlib
import importlib
import importlib.util
import os
import sys
from dataclasses import field
from pathlib import Path
from typing import Annotated, Any

from imdrive.config.validation import Str, setting, settings
from imdrive.errors import ConfigError


@settings("plugins")
class PluginSettings:
    """Estimators from the user's own modules (``[plugins]``)."""

    modules: Annotated[
        tuple[Str, ...],
        setting(
            "Python modules imported before the scenario is read, so the estimators they "
            "define are registered: dotted names on sys.path, or paths of .py files (importing "
            "runs the module's code: list only modules you trust)"
        ),
    ] = ()
    settings: Annotated[
        dict[str, dict[str, Any]],
        setting(
            "settings of each plug-in estimator, [plugins.settings.NAME] (the keys its "
            "settings class declares)"
        ),
    ] = field(default_factory=dict)

    def __hash__(self) -> int:
        # the settings tables are dicts: hash their repr (sorted), as equal tables repr equal
        return hash((self.modules, repr(sorted(self.settings.items()))))


#: the environment variable that allows plug-in modules (value ``1``)
ALLOW_ENV = "IMDRIVE_ALLOW_PLUGINS"
#: how to allow a plug-in, for the messages
HOW_TO_ALLOW = f"--allow-plugins, {ALLOW_ENV}=1 or allow_plugins=True"

_ALLOWED: contextvars.ContextVar[bool] = contextvars.ContextVar("imdrive_allow", default=False)
_LOOKING: contextvars.ContextVar[list | None] = contextvars.ContextVar(
    "imdrive_plugins_looking", default=None
)


def plugins_allowed() -> bool:
    """Whether a listed plug-in module may be imported now.

    Returns
    -------
    bool
        True inside :func:`allowing_plugins` or with ``IMDRIVE_ALLOW_PLUGINS=1``.
    """
    return _ALLOWED.get() or os.environ.get(ALLOW_ENV, "").strip() == "1"


@contextlib.contextmanager
def allowing_plugins(allow: bool | None = True):
    """Allow (or, with ``False``, forbid) importing listed plug-in modules in this block.

    Parameters
    ----------
    allow : bool or None
        True: allowed in the block; False or None: the rule is left as it is outside the
        block (the environment variable, an enclosing block).

    Yields
    ------
    None
    """
    if not allow:
        yield
        return
    token = _ALLOWED.set(True)
    try:
        yield
    finally:
        _ALLOWED.reset(token)


@contextlib.contextmanager
def looking():
    """A block that reads scenarios only to show them: no plug-in module is imported, even
    when allowed; the modules it would have imported are collected.

    Yields
    ------
    list of str
        The modules left unimported (filled as scenarios are read).
    """
    skipped: list[str] = []
    token = _LOOKING.set(skipped)
    try:
        yield skipped
    finally:
        _LOOKING.reset(token)


def looked_past() -> list[str]:
    """The modules left unimported so far inside :func:`looking` (empty outside it); while
    it is not empty, an estimator name no module registered may be the plug-in's, and its
    settings stay unchecked.

    Returns
    -------
    list of str
    """
    return list(_LOOKING.get() or ())


def _is_path(spec: str) -> bool:
    return spec.endswith(".py") or "/" in spec or "\\" in spec


def _module_name(path: Path) -> str:
    return "imdrive_plugin_" + hashlib.sha256(str(path).encode()).hexdigest()[:12]


def _file_of(spec: str) -> Path | None:
    """A path-like module's file, its links resolved; None where it cannot be (a loop of
    links, a name too long, a NUL byte), which :meth:`pathlib.Path.resolve` raises for."""
    try:
        return Path(spec).expanduser().resolve()
    except (OSError, RuntimeError, ValueError):
        return None


def is_imported(spec: str) -> bool:
    """Whether the module ``spec`` is already imported in this process (no code would run).

    Parameters
    ----------
    spec : str
        A dotted module name or a ``.py`` file's path.

    Returns
    -------
    bool
    """
    if _is_path(spec):
        path = _file_of(spec)
        return path is not None and _module_name(path) in sys.modules
    return spec in sys.modules


def resolve_plugin_paths(data, base_dir) -> None:
    """Make a file's relative ``[plugins] modules`` paths absolute, from the file's folder.

    Called on a file's own tables before any ``--set`` is applied (an override's path stays
    relative to the working directory), as for ``[machine] file``.

    Parameters
    ----------
    data : dict
        The TOML-shaped scenario as read (changed in place).
    base_dir : str or pathlib.Path or None
        The file's folder; ``None`` leaves the paths as they are.
    """
    plugins = data.get("plugins") if isinstance(data, dict) else None
    if base_dir is None or not isinstance(plugins, dict):
        return
    modules = plugins.get("modules")
    if not isinstance(modules, list | tuple):
        return
    plugins["modules"] = [
        str(Path(base_dir).resolve() / m)
        if isinstance(m, str) and _is_path(m) and not Path(m).expanduser().is_absolute()
        else m
        for m in modules
    ]


def module_file(spec: str) -> Path | None:
    """The file of module ``spec``, found without running any code (``None``: not found
    without importing, e.g. a sub-module of a package not yet imported)."""
    if _is_path(spec):
        return _file_of(spec)
    mod = sys.modules.get(spec)
    if mod is not None:
        f = getattr(mod, "__file__", None)
        return Path(f) if f else None
    if "." in spec and spec.rsplit(".", 1)[0] not in sys.modules:
        return None  # finding it would import its package
    try:
        found = importlib.util.find_spec(spec)
    except (ImportError, ValueError):
        return None
    origin = getattr(found, "origin", None)
    return Path(origin) if origin and origin not in ("built-in", "frozen") else None


def module_hashes(modules) -> dict[str, str | None]:
    """The sha256 of each module's file (``None`` where it cannot be read).

    Parameters
    ----------
    modules : sequence of str
        ``[plugins] modules``.

    Returns
    -------
    dict of str to str or None
        Module -> hex digest.
    """
    out: dict[str, str | None] = {}
    for spec in modules or ():
        if not isinstance(spec, str):
            continue
        f = module_file(spec)
        try:
            out[spec] = hashlib.sha256(f.read_bytes()).hexdigest() if f and f.is_file() else None
        except OSError:
            out[spec] = None
    return out


def changed_modules(recorded) -> list[str]:
    """The modules whose file is not the one a ``summary.json`` recorded.

    Parameters
    ----------
    recorded : dict
        Module -> sha256, as :func:`module_hashes` gave when the run was saved.

    Returns
    -------
    list of str
        Each changed (or now missing) module.
    """
    if not isinstance(recorded, dict):
        return []
    now = module_hashes([k for k in recorded if isinstance(k, str)])
    return [k for k, v in now.items() if isinstance(recorded.get(k), str) and v != recorded[k]]


def import_plugin(spec: str, where: str = "plugins.modules") -> None:
    """Import the module ``spec`` (a dotted name, or a ``.py`` file's path) once.

    Parameters
    ----------
    spec : str
        The module.
    where : str
        The field named in an error.

    Raises
    ------
    ConfigError
        The module cannot be found or fails to import (its error in one line).
    """
    try:
        if _is_path(spec):
            from imdrive.config.user_files import path_form_problem, user_file_problem

            problem = path_form_problem(spec)
            if problem is not None:
                raise ConfigError(where, problem)
            path = _file_of(spec)
            if path is None:
                raise ConfigError(where, user_file_problem(spec, "Python file") or "not a file")
            name = _module_name(path)
            if name in sys.modules:
                return
            problem = user_file_problem(path, "Python file")
            if problem is not None:
                raise ConfigError(where, problem)
            mod_spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(mod_spec)
            sys.modules[name] = module
            try:
                mod_spec.loader.exec_module(module)
            except BaseException:
                del sys.modules[name]
                raise
        else:
            importlib.import_module(spec)
    except ConfigError:
        raise
    except Exception as exc:  # the user's module: its own error, in one line
        raise ConfigError(where, f"cannot import {spec!r}: {type(exc).__name__}: {exc}") from None


def import_plugins(modules) -> None:
    """Import every module of a ``[plugins] modules`` list, if the user allows it.

    A module already imported runs nothing and passes; inside :func:`looking` none is
    imported (each is collected); otherwise each needs :func:`plugins_allowed`.

    Parameters
    ----------
    modules : sequence of str
        ``[plugins] modules``.

    Raises
    ------
    ConfigError
        A module that is not a string, is not allowed (naming it and how to allow it), or
        cannot be imported (:func:`import_plugin`).
    """
    for i, spec in enumerate(modules or ()):
        where = f"plugins.modules[{i}]"
        if not isinstance(spec, str):
            raise ConfigError(where, f"must be a string, got {type(spec).__name__}")
        if not spec.strip():
            raise ConfigError(where, "is empty: a module name or a .py file's path")
        if is_imported(spec):
            continue
        skipped = _LOOKING.get()
        if skipped is not None:
            if spec not in skipped:
                skipped.append(spec)
            continue
        if not plugins_allowed():
            raise ConfigError(
                where,
                f"the plug-in module {spec!r} is not imported: importing runs its code, so a "
                f"plug-in runs only when you allow it ({HOW_TO_ALLOW})",
            )
        import_plugin(spec, where)


def module_spec_of(cls: type) -> str | None:
    """How a later process imports the module defining ``cls``: its dotted name, or its file
    for a module loaded from a path; ``None`` for the package's own and for ``__main__``."""
    mod = sys.modules.get(cls.__module__)
    name = cls.__module__
    if name.startswith("imdrive.") or name == "__main__" or mod is None:
        return None
    if name.startswith("imdrive_plugin_"):
        return getattr(mod, "__file__", None)
    return name
