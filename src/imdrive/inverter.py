"""Deprecated (0.1 layout): the names now live in
:mod:`imdrive.config.inverter`,
:mod:`imdrive.kernels.inverter`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.config.inverter", "imdrive.kernels.inverter")
