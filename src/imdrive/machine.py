"""Deprecated (0.1 layout): the names now live in
:mod:`imdrive.config.machine`,
:mod:`imdrive.kernels.machine`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.config.machine", "imdrive.kernels.machine")
