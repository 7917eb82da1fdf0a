"""Stability maps of the sensorless drive: steady state, small-signal model, maps.

* :func:`operating_point`: the steady state of the whole closed loop at one (speed, load)
  point and its discrete small-signal model (:class:`~imdrive.stability.linear.OperatingPoint`,
  ``to_statespace()``);
* :func:`stability_map`: the least stable mode over a speed x torque grid (a DataFrame);
* :func:`validate_map`: the map's verdicts against simulations from each fixed point.

Method and results: ``docs/stability.md``.
"""

from imdrive.stability.linear import OperatingPoint, map_scenario, operating_point
from imdrive.stability.maps import stability_map, validate_map

__all__ = ["OperatingPoint", "map_scenario", "operating_point", "stability_map", "validate_map"]
