"""Deprecated (0.1 layout): the names now live in
:mod:`imdrive.run.batch`,
:mod:`imdrive.kernels.batch`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.run.batch", "imdrive.kernels.batch")
