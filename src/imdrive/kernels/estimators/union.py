"""Several estimators in one compiled loop: the records of a batch whose drives differ by
estimator.

The loop is compiled for the *type* of its estimator's records (:mod:`.registry`), so a batch
of five estimators compiled the drive five times: the first ``imdrive bench-estimators`` after
a warm ``imdrive run`` spent 22 of its 47 s of compilation on five copies of the loop, and 12 s
more on five copies of the batch's own functions (``benchmarks/bench_compile.py``,
2026-12-02). A batch now gives such drives *union* records instead (:func:`union_of`): a
selector, then every registered estimator's parameter (state) record as a nested record. The
generic entry points below (``estimator_step``, ``estimator_log``, ``estimator_finite``,
``estimator_flux``, ``estimator_flux_magnitude``) run the selected one: each is one compiled
function that branches on the selector (called, not inlined: numba compiles an inlined
implementation once to type the call and again in the loop); the estimators' own functions are
unchanged and compiled into the one loop. Numba reads and writes a nested record in place, so
each drive runs exactly the code and the arithmetic it runs alone, and its results are the same
bits (a test).

The union holds every registered estimator, whichever the batch runs, so that batches of
different subsets (``--estimators mras,afo`` after a full bench, a sweep over two) share one
compiled loop. Its first field is named after the members: numba passes a record where one of
a prefix of its fields is expected, and two unions must never be taken for one another.
"""

from __future__ import annotations

import functools
import re
from typing import NamedTuple

import numpy as np
from numba import types
from numba.extending import overload
from numba.np.numpy_support import as_dtype

from imdrive.kernels.estimators.registry import (
    EstimatorKernel,
    estimator_finite,
    estimator_flux,
    estimator_flux_magnitude,
    estimator_log,
    estimator_step,
    kernel,
    kernel_names,
    kernel_of_state,
)
from imdrive.kernels.jit import IMPL
from imdrive.kernels.records import i8

#: The entry points compile the steps of every registered estimator (as the registry's do).
_CACHE_FOLLOWS_IMPORTERS = True

_SEL = "union__"


@functools.cache
def _union(ks: tuple[EstimatorKernel, ...]) -> tuple[np.dtype, np.dtype]:
    sel = _SEL + "__".join(re.sub(r"\W", "_", k.name) for k in ks)
    params = np.dtype([(sel, i8)] + [(f"m{j}", k.params) for j, k in enumerate(ks)])
    state = np.dtype([(sel, i8)] + [(f"m{j}", k.state) for j, k in enumerate(ks)])
    return params, state


def union_of() -> tuple[np.dtype, np.dtype]:
    """The union parameter and state record dtypes of every registered estimator (by name:
    the same records whatever order they registered in)."""
    return _union(tuple(kernel(n) for n in sorted(kernel_names())))


def members(dtype: np.dtype) -> tuple[EstimatorKernel, ...] | None:
    """The estimators of a union record dtype, in its order (None: not a union). Read from
    the records themselves, so that a helper process that built none knows them."""
    dtype = np.dtype(dtype)
    if not dtype.names or not dtype.names[0].startswith(_SEL):
        return None
    return tuple(kernel_of_state(dtype.fields[n][0]) for n in dtype.names[1:])


def state_of(params: np.dtype) -> np.dtype:
    """The union state dtype that goes with the union parameter dtype ``params``."""
    return _union(members(params))[1]


class _Logging(NamedTuple):
    log_fields: tuple[str, ...]


def logged(dtype: np.dtype):
    """What :func:`imdrive.kernels.engine.log_dtype` reads of the estimator of records
    ``dtype``: its kernel, or for a union every member's log fields (each drive's own are
    taken back from them: :func:`imdrive.run.batch.simulate_batch`)."""
    ks = members(dtype)
    if ks is None:
        return kernel_of_state(dtype)
    return _Logging(tuple(dict.fromkeys(f for k in ks for f in k.log_fields)))


def to_union(dtype: np.dtype, rows: list[np.ndarray]) -> np.ndarray:
    """The union records (``dtype``, :func:`union_of`) of one-row records ``rows`` of
    estimators of the union (params or states: as ``dtype``), zeros in the others' places."""
    out = np.zeros(len(rows), dtype=dtype)
    sel = dtype.names[0]
    placed = 0
    for j in range(len(members(dtype))):
        own = dtype.fields[f"m{j}"][0]
        idx = [g for g, r in enumerate(rows) if r.dtype == own]
        if idx:
            out[sel][idx] = j
            out[f"m{j}"][idx] = np.concatenate([rows[g] for g in idx])
            placed += len(idx)
    if placed != len(rows):  # an estimator registered after the union was made
        raise ValueError(f"{len(rows) - placed} records of no estimator of the union {sel}")
    return out


def from_union(rows: np.ndarray) -> np.ndarray:
    """The selected estimator's own records of union records ``rows`` (all of one member)."""
    j = int(rows[rows.dtype.names[0]][0])
    return rows[f"m{j}"].copy()


def _members_of(s):
    if not isinstance(s, types.Record) or not next(iter(s.fields), "").startswith(_SEL):
        return None
    return members(as_dtype(s))


def _dispatch(s, args: str, name: str, member):
    """The implementation, as source compiled here, of a call on the selected member:
    ``member(k, j)`` gives the expression for member ``j`` (estimator ``k``) and the globals
    it names. The members' own functions are called directly, not through the registry's
    generic entry points: two inlined calls per member and entry point were 1.3 s of the
    union loop's compile."""
    ks = _members_of(s)
    if ks is None:
        return None
    scope: dict = {}
    exprs = []
    for j, k in enumerate(ks):
        expr, names = member(k, j)
        exprs.append(expr)
        scope.update(names)
    lines = [f"def {name}({args}):", f"    j = s.{next(iter(s.fields))}"]
    for j, expr in enumerate(exprs[:-1]):
        lines += [f"    if j == {j}:", f"        return {expr}"]
    lines.append(f"    return {exprs[-1]}")
    exec("\n".join(lines), scope)  # noqa: S102  (source made here from member indices)
    return scope[name]


def _call(f, expr: str, j: int, default: str):
    """``expr`` calling ``f`` as ``f{j}``, or ``default`` if the member has no ``f``."""
    return (expr, {f"f{j}": f}) if f is not None else (default, {})


@overload(estimator_step, inline="never", jit_options=IMPL)
def _union_step(p, model, s, inp):
    return _dispatch(
        s,
        "p, model, s, inp",
        "union_step",
        lambda k, j: _call(k.step, f"f{j}(p.m{j}, model, s.m{j}, inp)", j, ""),
    )


@overload(estimator_log, inline="never", jit_options=IMPL)
def _union_log(row, p, s, n_p):
    fields = set(getattr(row, "fields", None) or ())

    def member(k, j):  # a log record without its fields logs nothing, as the registry's
        f = k.log if set(k.log_fields) <= fields else None
        return _call(f, f"f{j}(row, p.m{j}, s.m{j}, n_p)", j, "None")

    return _dispatch(s, "row, p, s, n_p", "union_log", member)


@overload(estimator_finite, inline="never", jit_options=IMPL)
def _union_finite(s):
    return _dispatch(
        s, "s", "union_finite", lambda k, j: _call(k.finite, f"f{j}(s.m{j})", j, "True")
    )


@overload(estimator_flux, inline="never", jit_options=IMPL)
def _union_flux(s):
    return _dispatch(s, "s", "union_flux", lambda k, j: _call(k.flux, f"f{j}(s.m{j})", j, "0j"))


@overload(estimator_flux_magnitude, inline="never", jit_options=IMPL)
def _union_flux_magnitude(s):
    return _dispatch(
        s,
        "s",
        "union_flux_magnitude",
        lambda k, j: _call(k.flux_magnitude, f"f{j}(s.m{j})", j, "0.0"),
    )
