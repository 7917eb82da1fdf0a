"""Deprecated (0.1 layout): the names now live in :mod:`imdrive.run.plots`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.run.plots")
