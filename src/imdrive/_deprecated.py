"""Old import paths of the first release, kept for one release (0.2) with a DeprecationWarning.

``imdrive.scenario``, ``imdrive.simulate``, ``imdrive.batch``, ... moved into the layer
packages (``config``, ``kernels``, ``design``, ``run``, ``studies``). No file is left at the
old paths: :data:`OLD_PATHS` maps each to the modules that hold its names now, and a finder on
``sys.meta_path`` (:func:`install`, called by ``imdrive/__init__.py``) builds the old module on
import from them (:func:`reexport`), so users' scripts keep working and are told where the
names went.

``imdrive.simulate`` is also the top-level function; importing the old module of that name
sets the package's attribute to the module, so that module is callable: both
``imdrive.simulate(sc)`` and ``from imdrive.simulate import simulate`` keep working.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
import warnings

REMOVED_IN = "0.3"

#: old module -> the modules whose names it offers (first one wins on a clash)
OLD_PATHS: dict[str, tuple[str, ...]] = {
    "imdrive.batch": ("imdrive.run.batch", "imdrive.kernels.batch"),
    "imdrive.compensator": ("imdrive.kernels.compensator",),
    "imdrive.control": ("imdrive.kernels.ifoc", "imdrive.design.gains"),
    "imdrive.engine": ("imdrive.kernels.engine",),
    "imdrive.inverter": ("imdrive.config.inverter", "imdrive.kernels.inverter"),
    "imdrive.layout": ("imdrive.kernels.engine", "imdrive.kernels.profiles"),
    "imdrive.machine": ("imdrive.config.machine", "imdrive.kernels.machine"),
    "imdrive.mras": ("imdrive.kernels.estimators.mras", "imdrive.design.gains"),
    "imdrive.paper": ("imdrive.studies.paper",),
    "imdrive.plots": ("imdrive.run.plots",),
    "imdrive.profiles": (
        "imdrive.config.profiles",
        "imdrive.kernels.profiles",
        "imdrive.run._profiles",
    ),
    "imdrive.result": ("imdrive.run.result",),
    "imdrive.scenario": (
        "imdrive.config.scenario",
        "imdrive.config.presets",
        "imdrive.config.overrides",
    ),
    "imdrive.simulate": ("imdrive.run.simulate", "imdrive.run.build"),
}


def reexport(old: str, *new: str) -> None:
    """Fill module ``old`` with every name of the modules ``new`` and warn once per import.

    Private names are copied too: scripts of the first release reached for a few of them.

    Parameters
    ----------
    old : str
        The old module's name; it must be in ``sys.modules``.
    *new : str
        The modules that hold its names now.
    """
    ns = sys.modules[old].__dict__
    for name in new:
        mod = importlib.import_module(name)
        for key, val in vars(mod).items():
            if not (key.startswith("__") and key.endswith("__")):
                ns.setdefault(key, val)
    warnings.warn(
        f"{old} is deprecated and will be removed in imdrive {REMOVED_IN}: "
        f"import from {' / '.join(new)} instead",
        DeprecationWarning,
        stacklevel=3,  # reexport, exec_module, then (importlib's frames skipped) the import
    )


class _CallableModule(types.ModuleType):
    """The old ``imdrive.simulate`` module, callable as the function of the same name."""

    def __call__(self, *args, **kwargs):
        return self.simulate(*args, **kwargs)


class _OldPathLoader(importlib.abc.Loader):
    def create_module(self, spec):
        cls = _CallableModule if spec.name == "imdrive.simulate" else types.ModuleType
        module = cls(spec.name)
        module.__doc__ = "Deprecated (0.1 layout): the names now live in " + ", ".join(
            f":mod:`{m}`" for m in OLD_PATHS[spec.name]
        )
        return module

    def exec_module(self, module):
        reexport(module.__name__, *OLD_PATHS[module.__name__])


class _OldPathFinder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        if fullname not in OLD_PATHS:
            return None
        return importlib.machinery.ModuleSpec(fullname, _LOADER, origin="imdrive._deprecated")


_LOADER = _OldPathLoader()


def install() -> None:
    """Put the finder of the old import paths on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _OldPathFinder) for f in sys.meta_path):
        sys.meta_path.append(_OldPathFinder())
