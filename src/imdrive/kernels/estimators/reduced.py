"""The estimators' states in the stability maps' reduced state: two generic entry points.

:func:`estimator_reduce` and :func:`estimator_restore` call the ``reduce`` and ``restore``
functions of the estimator whose state record they receive (its
:class:`~imdrive.kernels.estimators.registry.ReducedState`), resolved by numba from the
record's type as :func:`~imdrive.kernels.estimators.registry.estimator_step` is. They live
apart from the registry so that only the stability kernels (:mod:`imdrive.kernels.linearise`)
import them: the registry's cache follows every module that imports it
(:mod:`imdrive._cache`), and an edit of the map's kernels must not compile the drive again.
"""

from __future__ import annotations

from numba.extending import overload

from imdrive.kernels.estimators.registry import ReducedState, _lookup, kernel_of_state
from imdrive.kernels.jit import CACHED_IMPL


def reduced_state_of(S) -> ReducedState:
    """The ``ReducedState`` of the estimator whose records drive state ``S`` carries
    (``ValueError`` naming the estimator where it has none)."""
    k = kernel_of_state(S.est.dtype)
    if k.reduced is None:
        raise ValueError(f'the estimator "{k.name}" gives the stability maps no reduced state')
    return k.reduced


def estimator_reduce(p, s, c, z, k):
    """Write the estimator's states into the maps' reduced state (compiled code only)."""
    raise NotImplementedError("estimator_reduce is called from compiled code only")


def estimator_restore(z, k, s):
    """Write the maps' reduced state back into the estimator's record (compiled code only)."""
    raise NotImplementedError("estimator_restore is called from compiled code only")


@overload(estimator_reduce, inline="always", jit_options=CACHED_IMPL)
def _estimator_reduce(p, s, c, z, k):
    e = _lookup(s)
    if e is None or e.reduced is None:
        return None
    reduce = e.reduced.reduce
    return lambda p, s, c, z, k: reduce(p, s, c, z, k)


@overload(estimator_restore, inline="always", jit_options=CACHED_IMPL)
def _estimator_restore(z, k, s):
    e = _lookup(s)
    if e is None or e.reduced is None:
        return None
    restore = e.reduced.restore
    return lambda z, k, s: restore(z, k, s)
