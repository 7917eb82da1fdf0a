"""Deprecated (0.1 layout): the names now live in
:mod:`imdrive.config.scenario`,
:mod:`imdrive.config.presets`,
:mod:`imdrive.config.overrides`."""

from imdrive._deprecated import reexport

reexport(__name__, "imdrive.config.scenario", "imdrive.config.presets", "imdrive.config.overrides")
