"""R2 laws as plug-ins: one decision contract, one registry, dispatch by record type.

An R2 law turns each accepted decision window of the R2 compensator into a new ``R2_hat``. The
compensator owns the excitation (the injection), the detection (the synchronous demodulation
of the running estimator's flux error, or the detector's own: kernels/flux_detector.py) and
the gating (kernels/gating.py); the law only decides. A law registered here
(:func:`register_law`) has its own parameter and state records, carried inside the
compensator's (``COMPENSATOR_PARAMS.law``, ``COMPENSATOR_STATE.law``), and the compensator
calls it through :func:`law_decide` and :func:`law_hold`, which numba resolves at compile time
from the *type* of the law's state record, as the estimators' steps are resolved
(:mod:`imdrive.kernels.estimators.registry`): a drive with a plug-in law compiles its own loop
and holds no branch per law.

The package's two laws, the paper's fuzzy table and the Kalman filter on R2
(:mod:`imdrive.kernels.r2_kalman`), keep their fields in the compensator's records and share
one compiled loop: a drive switching between them compiles nothing (one compilation of the
drive is 40-55 s on these machines, benchmarks/README.md). The placeholder law
(:data:`NO_LAW_PARAMS`, :data:`NO_LAW_STATE`) fills the slot then.

The contract
------------
``decide(p, s, m, w) -> R2`` (ohm)
    ``p``, ``s``: the law's parameter and state records (``s`` updated in place); ``m``: the
    controller's machine model (:data:`imdrive.kernels.model.MODEL_STATE`, read-only here: the
    compensator writes the returned value into ``m.R2_hat``, clamped to ``[w.R2_min,
    w.R2_max]``); ``w``: the :class:`LawWindow` of the decision.
``hold(p, s, m, w)`` (optional)
    A decision window the gating rejected (a transient, the voltage limit, the injection's
    start): no measurement. ``w.E`` and ``w.r`` are 0.
``log(row, s)`` (optional)
    Writes the law's own ``log_fields`` (float64) into the log record ``row`` at every logged
    sample (their units are declared with the settings half, ``log_units``).

A user's law is a module outside the package that registers its kernel here and its settings
class with :func:`imdrive.config.r2_laws.r2_law` (no section: its table is
``[plugins.settings.NAME]``), listed in the scenario's ``[plugins] modules`` and selected with
``compensator.step_law = "NAME"`` (docs/architecture.md; tests/data/own_r2_law.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numba import types
from numba.extending import overload
from numba.np.numpy_support import as_dtype

from imdrive.kernels.jit import CACHED_IMPL
from imdrive.kernels.plugin_registry import Registry, source_tag, tagged
from imdrive.kernels.records import record_dtype

#: The generic entry points below compile the decision of whichever law registered here, so
#: their cache follows every module that imports this one (:mod:`imdrive._cache`).
_CACHE_FOLLOWS_IMPORTERS = True

#: The law slot of a drive whose law is the package's table or Kalman law (or none).
NO_LAW_PARAMS = record_dtype([("law_none", np.uint8)])
NO_LAW_STATE = record_dtype([("law_none_state", np.uint8)])


class LawWindow(NamedTuple):
    """What the compensator hands a law at a decision (SI units).

    Attributes
    ----------
    E : float
        The window's mean detected in-phase flux error, Wb (the injection's synchronous
        detection, averaged over whole injection periods).
    r : float
        The relative R2 error it measures, ``R2_hat/R2 - 1 = -E / (L a S(w_i T2_hat))``
        (:func:`imdrive.kernels.r2_kalman.relative_error`: the analytic sensitivity at the
        injection's frequency and amplitude in use); 0 where the sensitivity vanishes.
    T : float
        The decision period, s.
    R2_min, R2_max : float
        The clamps the compensator applies to the returned value, ohm.
    """

    E: float
    r: float
    T: float
    R2_min: float
    R2_max: float


@dataclass(frozen=True)
class LawKernel:
    """The compiled half of an R2 law: its records and its numba functions.

    Attributes
    ----------
    name : str
        The value of ``compensator.step_law`` that selects it.
    params, state : numpy.dtype
        Its record dtypes, as registered: each with a tag field that makes it unique (and,
        for a law outside the package, carries a hash of its module's name and text, so an
        edited law is compiled afresh).
    decide, hold, log : numba dispatcher
        See the module docstring (``hold`` and ``log`` may be None).
    log_fields : tuple of str
        Its own log fields, written by ``log``.
    """

    name: str
    params: np.dtype
    state: np.dtype
    decide: object
    hold: object = None
    log_fields: tuple[str, ...] = ()
    log: object = None
    source: str = field(default="", compare=False)


_REGISTRY = Registry("R2 law")
_BY_STATE = _REGISTRY.by_record


def register_law(
    name: str, params: np.dtype, state: np.dtype, decide, hold=None, log_fields=(), log=None
) -> LawKernel:
    """Register an R2 law's compiled half under ``name`` and return it.

    Parameters
    ----------
    name : str
        The ``compensator.step_law`` value that selects it.
    params, state : numpy.dtype
        Its record dtypes (fields by name; :mod:`imdrive.kernels.records`).
    decide, hold : numba dispatcher
        ``decide(p, s, m, w) -> R2`` and, optional, ``hold(p, s, m, w)`` (module docstring).
    log_fields : sequence of str
        Its own log fields (float64), written by ``log(row, s)``.

    Returns
    -------
    LawKernel
        With ``params`` and ``state`` extended by a tag field. Registering a name again
        replaces the entry (a re-imported user module).
    """
    tag = source_tag(decide)
    kernel = LawKernel(
        name=name,
        params=tagged(np.dtype(params), f"law_{name}", tag),
        state=tagged(np.dtype(state), f"law_{name}_state", tag),
        decide=decide,
        hold=hold,
        log_fields=tuple(log_fields),
        log=log,
        source=tag,
    )
    return _REGISTRY.add(kernel)


def law_kernel(name: str) -> LawKernel:
    """The registered law ``name`` (``KeyError`` naming the registered ones)."""
    return _REGISTRY[name]


def law_of_records(comp_dtype: np.dtype) -> LawKernel | None:
    """The plug-in law in the ``law`` slot of a compensator record dtype (None: the
    placeholder, the package's laws)."""
    return _BY_STATE.get(np.dtype(comp_dtype.fields["law"][0]))


def law_kernel_names() -> tuple[str, ...]:
    """Names of every registered plug-in law, in registration order."""
    return _REGISTRY.names()


def compensator_dtypes(base_params: np.dtype, base_state: np.dtype, law: LawKernel | None):
    """The compensator's record dtypes with ``law``'s records in the ``law`` slot (the
    placeholder's for ``None``)."""
    if law is None:
        return base_params, base_state

    def with_law(base, sub):
        return np.dtype([(n, sub if n == "law" else base.fields[n][0]) for n in base.names])

    return with_law(base_params, law.params), with_law(base_state, law.state)


def _lookup(s) -> LawKernel | None:
    if not isinstance(s, types.Record):
        return None
    return _BY_STATE.get(as_dtype(s))


def _is_placeholder(s) -> bool:
    return isinstance(s, types.Record) and as_dtype(s) == NO_LAW_STATE


# --- generic entry points, resolved by numba from the law state record's type ---------------


def law_decide(p, s, m, w):
    """The new R2_hat of the law whose state is ``s`` (compiled code only)."""
    raise NotImplementedError("law_decide is called from compiled code only")


def law_hold(p, s, m, w):
    """A rejected window for the law whose state is ``s`` (compiled code only)."""
    raise NotImplementedError("law_hold is called from compiled code only")


def law_log(row, s):
    """Write the law's own log fields (compiled code only)."""
    raise NotImplementedError("law_log is called from compiled code only")


@overload(law_decide, inline="always", jit_options=CACHED_IMPL)
def _law_decide(p, s, m, w):
    if _is_placeholder(s):
        return lambda p, s, m, w: m.R2_hat  # the package's laws decide in the compensator
    k = _lookup(s)
    if k is None:
        return None
    decide = k.decide

    def impl(p, s, m, w):
        return decide(p, s, m, w)

    return impl


@overload(law_hold, inline="always", jit_options=CACHED_IMPL)
def _law_hold(p, s, m, w):
    k = None if _is_placeholder(s) else _lookup(s)
    if k is None or k.hold is None:
        if _is_placeholder(s) or k is not None:

            def nothing(p, s, m, w):
                pass

            return nothing
        return None
    hold = k.hold

    def impl(p, s, m, w):
        hold(p, s, m, w)

    return impl


@overload(law_log, inline="always", jit_options=CACHED_IMPL)
def _law_log(row, s):
    k = None if _is_placeholder(s) else _lookup(s)
    if k is None or k.log is None:
        if _is_placeholder(s) or k is not None:

            def nothing(row, s):
                pass

            return nothing
        return None
    log = k.log

    def impl(row, s):
        log(row, s)

    return impl
