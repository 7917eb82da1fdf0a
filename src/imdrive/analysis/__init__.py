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

Every public name is re-exported here, its module imported on first use.
"""

from __future__ import annotations

import importlib

#: Each public name and the module it comes from, imported on first use (PEP 562): the
#: modules load scipy.optimize and matplotlib's helpers, 0.3 s that a run's status, which
#: needs only :mod:`imdrive.analysis.observability`, paid through this package (2026-11-30).
_EXPORTS = {
    "SteadyState": "circuit",
    "breakdown": "circuit",
    "breakdown_thevenin": "circuit",
    "equivalent_circuit": "circuit",
    "LockedRotorTest": "circuit_from_tests",
    "NoLoadTest": "circuit_from_tests",
    "TestCircuit": "circuit_from_tests",
    "circuit_from_tests": "circuit_from_tests",
    "plot_speed_error_vs_R2": "figures",
    "FOCOperatingPoint": "foc",
    "detuning_speed_error_rpm": "foc",
    "field_weakened_flux_Wb": "foc",
    "foc_operating_point": "foc",
    "Nameplate": "nameplate",
    "NameplateFit": "nameplate",
    "estimate_circuit": "nameplate",
    "estimate_circuit_lee": "nameplate",
}

__all__ = list(_EXPORTS)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
