"""Steady-state analysis: equivalent circuit, breakdown torque, field-oriented operating point.

Pure numpy/scipy (no numba): the package depends only on :mod:`imdrive.config.machine` and
:mod:`imdrive.errors`, so it can be used without compiling any kernel. SI units throughout; rpm
only where a name says so; phasors are peak-value phasors (amplitude-invariant Clarke transform,
see :mod:`imdrive`).

* :mod:`imdrive.analysis.circuit` — the exact T-equivalent circuit (:func:`equivalent_circuit`,
  :class:`SteadyState`) and the breakdown torque (:func:`breakdown`,
  :func:`breakdown_thevenin`);
* :mod:`imdrive.analysis.foc` — the steady state of an indirect-FOC drive with a wrong rotor
  resistance estimate (:func:`foc_operating_point`, :class:`FOCOperatingPoint`) and the
  sensorless detuning law (:func:`detuning_speed_error_rpm`), derived in that module's
  docstring together with its relation to the paper's eq. (10);
* :mod:`imdrive.analysis.figures` — :func:`plot_speed_error_vs_R2` (matplotlib, imported
  lazily);
* :mod:`imdrive.analysis.nameplate` — the equivalent circuit estimated from nameplate and
  catalogue data (:class:`Nameplate`, :func:`estimate_circuit`, and the published
  nameplate-only method of Lee, Frank, Sen et al., :func:`estimate_circuit_lee`, whose
  equations are in :mod:`imdrive.analysis.nameplate_lee`);
* :mod:`imdrive.analysis.circuit_from_tests` — the circuit from a DC stator resistance, a
  no-load and a locked-rotor test (:func:`circuit_from_tests`).

Every public name is re-exported here.
"""

from __future__ import annotations

from imdrive.analysis.circuit import (
    SteadyState,
    breakdown,
    breakdown_thevenin,
    equivalent_circuit,
)
from imdrive.analysis.circuit_from_tests import (
    LockedRotorTest,
    NoLoadTest,
    TestCircuit,
    circuit_from_tests,
)
from imdrive.analysis.figures import plot_speed_error_vs_R2
from imdrive.analysis.foc import (
    FOCOperatingPoint,
    detuning_speed_error_rpm,
    field_weakened_flux_Wb,
    foc_operating_point,
)
from imdrive.analysis.nameplate import (
    Nameplate,
    NameplateFit,
    estimate_circuit,
    estimate_circuit_lee,
)

__all__ = [
    "SteadyState",
    "FOCOperatingPoint",
    "equivalent_circuit",
    "breakdown",
    "breakdown_thevenin",
    "foc_operating_point",
    "detuning_speed_error_rpm",
    "field_weakened_flux_Wb",
    "plot_speed_error_vs_R2",
    "Nameplate",
    "NameplateFit",
    "estimate_circuit",
    "estimate_circuit_lee",
    "NoLoadTest",
    "LockedRotorTest",
    "TestCircuit",
    "circuit_from_tests",
]
