"""The standstill R1 identification's former home (until 2026-11-29): it is the controller's
block now, run whatever the speed estimator, in :mod:`imdrive.kernels.r1_standstill`; these
names keep working."""

from imdrive.kernels.r1_standstill import (  # noqa: F401
    R1_DC_MIN_WINDOW,
    level_window,
    r1_standstill,
    r1_two_levels,
)

#: The function's former name.
mras_r1_standstill = r1_standstill
