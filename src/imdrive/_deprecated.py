"""Old import paths of the first release, kept for one release (0.2) with a DeprecationWarning.

``imdrive.scenario``, ``imdrive.simulate``, ``imdrive.batch``, ... moved into the layer
packages (``config``, ``kernels``, ``design``, ``run``, ``studies``). Each old module is now a
two-line file that calls :func:`reexport`, so users' scripts keep working and are told where
the names went.
"""

from __future__ import annotations

import importlib
import sys
import warnings

REMOVED_IN = "0.3"


def reexport(old: str, *new: str) -> None:
    """Fill module ``old`` with every name of the modules ``new`` and warn once per import.

    Private names are copied too: scripts of the first release reached for a few of them.
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
        stacklevel=3,
    )
