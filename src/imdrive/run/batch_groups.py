"""A batch's groups of drives and their records: which drives share one kernel call, and the
records of that call (:func:`stack_drives`), built from the drives' own (:mod:`imdrive.run.batch`).

Drives share a call where their records have one type: the same decimation of the log, the same
R2 law's records and the same estimator's, or any estimators in the union of every registered
one (:func:`united`, :mod:`imdrive.kernels.estimators.union`).
"""

from __future__ import annotations

import numpy as np

from imdrive.kernels import features
from imdrive.kernels.batch import BATCH_METRICS, BatchOut, new_scratch
from imdrive.kernels.engine import DriveParams, DriveState, log_dtype
from imdrive.kernels.estimators import union
from imdrive.kernels.profiles import N_PROF
from imdrive.kernels.r2_law_registry import law_of_records
from imdrive.run.metrics import lost_control_check, steady_window_periods
from imdrive.run.simulate import new_log


def stack_drives(arrays, est: np.dtype | None = None) -> tuple[DriveParams, DriveState]:
    """Stack one-drive :class:`DriveArrays` into the (N,)-row records of one kernel call.

    Profiles with different numbers of breakpoints are padded (the kernel reads ``prof_n``
    of them); fuzzy tables are shared (the distinct tables plus an index per drive). With
    ``est`` a union parameter dtype (:func:`imdrive.kernels.estimators.union.union_of`), the
    drives may differ by estimator: their estimator records become union records.
    """
    G = len(arrays)
    K = max(a.params.prof_t.shape[2] for a in arrays)
    prof_t = np.zeros((G, N_PROF, K))
    prof_v = np.zeros((G, N_PROF, K))
    table_idx = np.empty(G, dtype=np.int64)
    tables: list[np.ndarray] = []
    seen: dict[bytes, int] = {}
    for g, a in enumerate(arrays):
        k = a.params.prof_t.shape[2]
        prof_t[g, :, :k] = a.params.prof_t[0]
        prof_v[g, :, :k] = a.params.prof_v[0]
        table = a.params.tables[a.params.table_idx[0]]
        key = table.tobytes()
        if key not in seen:
            seen[key] = len(tables)
            tables.append(table)
        table_idx[g] = seen[key]
    united = est is not None and union.members(est) is not None
    records = {
        name: _rows([getattr(a.params, name) for a in arrays])
        for name in DriveParams._fields
        if name not in ("prof_t", "prof_v", "tables", "table_idx", "features")
        and not (united and name == "est")
    }
    if united:
        records["est"] = union.to_union(est, [a.params.est for a in arrays])
    params = DriveParams(
        **records,
        prof_t=prof_t,
        prof_v=prof_v,
        tables=np.ascontiguousarray(np.stack(tables)),
        table_idx=table_idx,
        features=features.of(records),  # the blocks some drive of the batch runs
    )
    state = DriveState(
        *(
            union.to_union(union.state_of(est), [a.state0.est for a in arrays])
            if united and f == "est"
            else _rows([getattr(a.state0, f) for a in arrays])
            for f in DriveState._fields
        )
    )
    return params, state


def _rows(arrs: list) -> np.ndarray:
    """``np.concatenate(arrs)`` along the first axis for arrays of one dtype, as bytes: numpy's
    own promotes a structured dtype field by field for every array (about 1 ms per drive for
    the drive's records, a third of a batch's set-up)."""
    dt = arrs[0].dtype
    if any(a.dtype is not dt and a.dtype != dt for a in arrs):
        return np.concatenate(arrs)
    raw = b"".join(np.ascontiguousarray(a).tobytes() for a in arrs)
    return np.frombuffer(raw, dtype=dt).reshape((-1, *arrs[0].shape[1:])).copy()


def group_args(items, n_rows: int, window_s: float, est: np.dtype | None = None):
    """``(params, state, log, out)`` of the kernel call of one group of (index, scenario,
    DriveArrays) sharing their records' dtypes (but for the estimator's, with ``est`` a
    union's: :func:`stack_drives`), the log ``n_rows`` long and NaN-filled."""
    G = len(items)
    arrays = [a for _, _, a in items]
    params, state = stack_drives(arrays, est)
    n_win = np.array(
        [steady_window_periods(sc, window_s, a.Ts, a.n_steps) for _, sc, a in items],
        dtype=np.int64,
    )
    lc = [lost_control_check(sc) for _, sc, _ in items]
    lc_bound = np.array([b for b, _ in lc])
    lc_n = np.array(
        [int(round(d / a.Ts)) for (_, d), a in zip(lc, arrays, strict=True)], dtype=np.int64
    )
    dtype = log_dtype(union.logged(params.est.dtype), law_of_records(params.comp.dtype))
    log = new_log((G, n_rows), dtype)
    out = BatchOut(
        n_steps=np.array([a.n_steps for a in arrays], dtype=np.int64),
        metrics=np.empty(G, dtype=BATCH_METRICS),
        status=np.empty(G, dtype=np.int64),
        k_end=np.empty(G, dtype=np.int64),
        n_win=n_win,
        lc_bound=lc_bound,
        lc_n=lc_n,
    )
    return params, state, log, out


def united(groups: dict) -> dict:
    """``groups`` with those that differ only by estimator joined into one whose records are
    the union of every registered estimator's (:mod:`imdrive.kernels.estimators.union`): one
    compiled loop for them all, not one per estimator. The first ``imdrive bench-estimators``
    after a warm ``imdrive run`` (five estimators) compiled 46.8 s in one process, 22.9 s so
    (benchmarks/README.md)."""
    by_rest: dict = {}
    for (le, est, comp), items in groups.items():
        by_rest.setdefault((le, comp), []).append((est, items))
    out = {}
    for (le, comp), parts in by_rest.items():
        if len(parts) == 1:
            out[(le, parts[0][0], comp)] = parts[0][1]
        else:
            out[(le, union.union_of()[0], comp)] = [it for _, items in parts for it in items]
    return out


def first_call(items, key: tuple, window_s: float) -> tuple:
    """The arguments of the batch worker's call for a group (its ``key``: ``(log_every, est
    dtype, comp dtype)``), made of its first drive with the blocks of every drive of the
    group compiled in (``params.features``, as :func:`stack_drives` has them): their types
    are what :func:`imdrive.run.prefetch.start_batch` compiles for."""
    log_every, est, _ = key
    params, state, log, out = group_args(items[:1], 0, window_s, est)
    blocks = {n for _, _, a in items for n in a.params.features.dtype.names[1:]}
    params = params._replace(features=np.ones(1, dtype=features.features_dtype(blocks)))
    return params, state, log, log_every, out, 0, 1, new_scratch(1, log.dtype)[0]


def own_rows(rows: np.ndarray, dtype: np.dtype) -> np.ndarray:
    """Log ``rows`` in the drive's own log ``dtype`` (a union group's log holds every
    estimator's fields)."""
    if rows.dtype == dtype:
        return rows
    own = np.empty(rows.shape, dtype=dtype)
    for name in dtype.names:
        own[name] = rows[name]
    return own
