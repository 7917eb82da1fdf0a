"""Estimators from outside the package: the ``[plugins]`` section and the import of modules.

A scenario that uses an estimator defined in the user's own module names that module in
``[plugins] modules`` (a dotted module name on ``sys.path``, or the path of a ``.py`` file);
reading the scenario imports it first, so the estimator registers itself (its settings class
with :func:`imdrive.config.estimators.estimator_settings`, its compiled half with
:func:`imdrive.kernels.estimators.registry.register_kernel`) before ``control.speed_feedback``
is checked. The estimator's settings are the table ``[plugins.settings.NAME]``. A scenario
built in Python after the module was imported gets the module added to ``modules``
automatically, so the scenario file it writes (``summary.json``), a sweep's worker process
and a rerun find the estimator again. Importing a module runs its code: a scenario file
that lists modules is as trustworthy as those modules.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
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


def _is_path(spec: str) -> bool:
    return spec.endswith(".py") or "/" in spec or "\\" in spec


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
            path = Path(spec).expanduser().resolve()
            name = "imdrive_plugin_" + hashlib.sha256(str(path).encode()).hexdigest()[:12]
            if name in sys.modules:
                return
            if not path.is_file():
                raise ConfigError(where, f"no such file: {spec}")
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
    """Import every module of a ``[plugins] modules`` list (see :func:`import_plugin`)."""
    for i, spec in enumerate(modules or ()):
        if not isinstance(spec, str):
            raise ConfigError(f"plugins.modules[{i}]", f"must be a string, got {spec!r}")
        import_plugin(spec, f"plugins.modules[{i}]")


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
