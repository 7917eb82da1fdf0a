"""Dotted-key overrides (``control.speed_ref_rpm=1500``): one mechanism for ``--set``, sweeps
and :meth:`~imdrive.config.scenario.Scenario.with_overrides`.

The functions live in :mod:`imdrive.config.scenario`, beside the settings classes whose keys
they check (so ``Scenario`` applies overrides without an import cycle); this module is their
public home.
"""

from imdrive.config.scenario import (
    _schema_allows,
    apply_override,
    is_setting,
    parse_override,
    set_path,
)

__all__ = ["_schema_allows", "apply_override", "is_setting", "parse_override", "set_path"]
