"""Compiled blocks: small numba functions of (parameters, state, inputs), and the loops that
compose them. Nothing here sees a Python object.

Every module of this package is compiled into a cache folder keyed on its own source and on the
kernel modules it imports (:mod:`imdrive._cache`) *by construction*: importing any
``imdrive.kernels.*`` module runs this file first, which installs the package's cache locator
and imports every module found below it. A new kernel module needs no registration;
``tests/package/test_layers.py`` checks that none escapes.
"""

import importlib
import pkgutil

from imdrive import _compiling
from imdrive._cache import kernel_cache

with kernel_cache():
    for _info in pkgutil.walk_packages(__path__, __name__ + "."):
        importlib.import_module(_info.name)
_compiling.attach()  # a word on the console while compiling, if the command line asked
