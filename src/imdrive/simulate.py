"""Deprecated (0.1 layout): the names now live in
:mod:`imdrive.run.simulate`,
:mod:`imdrive.run.build`.

``imdrive.simulate`` is also the top-level function; importing this old module would otherwise
replace that attribute of the package with the module, so the module is made callable: both
``imdrive.simulate(sc)`` and ``from imdrive.simulate import simulate`` keep working.
"""

import sys
import types

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.run.simulate", "imdrive.run.build")


class _CallableModule(types.ModuleType):
    def __call__(self, *args, **kwargs):
        return self.simulate(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
