"""R2 laws: what a user needs to add one, from a module of their own.

An R2 law has two halves registered under one name, the value of ``compensator.step_law``
that selects it:

* the compiled half -- parameter and state record dtypes, a numba ``decide(p, s, m, w)``
  returning the new ``R2_hat`` (ohm) from a decision window ``w`` (:class:`LawWindow`: the
  detected flux error, the relative R2 error it measures, the decision period, the clamps),
  and optionally ``hold(p, s, m, w)`` for a window the gating rejected --
  :func:`register_law` (:mod:`imdrive.kernels.r2_law_registry` has the contract);
* the Python half -- a settings class whose ``records(ctx)`` turns its settings and a
  :class:`LawContext` (R2_hat at the start, the decision period, the clamps) into its
  records' values -- :func:`r2_law` with no section (its keys are the scenario's
  ``[plugins.settings.NAME]`` table).

The compensator keeps the excitation, the detection and the gating; the law decides. Listed
in the scenario's ``[plugins] modules``, the module runs wherever the package's laws do
(``imdrive run``, batches, sweeps), with every speed estimator. ``docs/architecture.md`` has
the recipe and ``tests/data/own_r2_law.py`` an example.
"""

from __future__ import annotations

from imdrive.config.r2_laws import LawContext, LawRecords, r2_law
from imdrive.config.validation import Bool, Float, Int, setting
from imdrive.kernels.r2_law_registry import LawKernel, LawWindow, register_law
from imdrive.kernels.records import b1, f8, i8, record_dtype

__all__ = [
    "Bool",
    "Float",
    "Int",
    "LawContext",
    "LawKernel",
    "LawRecords",
    "LawWindow",
    "b1",
    "f8",
    "i8",
    "r2_law",
    "record_dtype",
    "register_law",
    "setting",
]
