"""Deprecated (0.1 layout): the names now live in
:mod:`imdrive.run.simulate`,
:mod:`imdrive.run.build`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.run.simulate", "imdrive.run.build")
