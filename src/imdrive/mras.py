"""Deprecated (0.1 layout): the names now live in
:mod:`imdrive.kernels.estimators.mras`,
:mod:`imdrive.design.gains`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.kernels.estimators.mras", "imdrive.design.gains")
