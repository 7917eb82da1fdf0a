"""Deprecated (0.1 layout): the names now live in
:mod:`imdrive.config.profiles`,
:mod:`imdrive.kernels.profiles`,
:mod:`imdrive.run._profiles`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.config.profiles", "imdrive.kernels.profiles", "imdrive.run._profiles")
