"""Deprecated (0.1 layout): the names now live in
:mod:`imdrive.kernels.ifoc`,
:mod:`imdrive.design.gains`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.kernels.ifoc", "imdrive.design.gains")
