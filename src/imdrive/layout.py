"""Deprecated (0.1 layout). The flat arrays and their index constants are gone: every block now
declares named records (see docs/architecture.md). The status codes and profile slots moved to
:mod:`imdrive.kernels.engine` and :mod:`imdrive.kernels.profiles`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.kernels.engine", "imdrive.kernels.profiles")
