"""imdrive: a fast simulator for sensorless induction-motor drives.

Conventions (used everywhere in the package)
--------------------------------------------
* SI units inside; rpm only at the edges (scenario files, exported columns).
* Space vectors use the **amplitude-invariant Clarke transform**::

      x_alpha = (2/3) (x_a - x_b/2 - x_c/2),   x_beta = (x_b - x_c) / sqrt(3)

  so ``i_alpha`` equals the phase-a current and the peak of a balanced phase quantity equals the
  magnitude of its space vector. Power and torque therefore carry the factor 3/2:
  ``p = 1.5 * (v_alpha*i_alpha + v_beta*i_beta)``, ``T_e = 1.5 * n_p * (psi_s x i_s)``.
* ``w_m`` is mechanical speed (rad/s), ``w_r = n_p * w_m`` electrical rotor speed (rad/s).
"""

from imdrive._cache import kernel_cache
from imdrive.errors import ConfigError, SimulationDiverged

# every compiled kernel is defined here, under the package's own cache folder (see _cache)
with kernel_cache():
    from imdrive import (  # noqa: F401
        batch,
        compensator,
        control,
        engine,
        fuzzy,
        inverter,
        machine,
        mras,
        profiles,
    )

from imdrive.machine import MachineParams, machine_preset, machine_presets  # noqa: E402

__version__ = "0.1.0"

__all__ = [
    "ConfigError",
    "SimulationDiverged",
    "MachineParams",
    "machine_preset",
    "machine_presets",
    "__version__",
]
