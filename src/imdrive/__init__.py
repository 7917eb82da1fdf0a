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

from imdrive import _deprecated
from imdrive.config.machine import MachineParams, machine_preset, machine_presets
from imdrive.errors import ConfigError, SimulationDiverged

_deprecated.install()  # the 0.1 import paths (imdrive.scenario, ...), with a DeprecationWarning

__version__ = "0.2.0.dev0"

# the layers (docs/architecture.md): config -> kernels -> design -> fuzzy/analysis -> run ->
# sweep/studies/plots -> cli. The most used names are importable from here; the run layer
# (and with it numba) loads on first use, so ``import imdrive`` stays light.
_LAZY = {
    "Scenario": "imdrive.config.scenario",
    "Profile": "imdrive.config.profiles",
    "simulate": "imdrive.run.simulate",
    "simulate_batch": "imdrive.run.batch",
    "SimulationResult": "imdrive.run.result",
    "BatchResult": "imdrive.run.batch",
    "replay": "imdrive.run.replay",
}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'imdrive' has no attribute {name!r}")


__all__ = [
    "BatchResult",
    "ConfigError",
    "MachineParams",
    "Profile",
    "Scenario",
    "SimulationDiverged",
    "SimulationResult",
    "__version__",
    "machine_preset",
    "machine_presets",
    "replay",
    "simulate",
    "simulate_batch",
]
