"""The optional blocks a drive compiles: chosen from its records before numba types the loop.

The loop branches on its records at run time (the R2 tracking runs where the compensator's
record says so, the switching bridge where the inverter's does), so a drive that never takes a
branch still had numba type and lower the block behind it: every ``imdrive run`` compiled the
whole engine, about 120 functions whatever the drive used (``benchmarks/bench_compile.py``).
Here each optional block is a *feature*: a predicate on the drive's records says whether a
drive runs it, and :class:`~imdrive.kernels.engine.DriveParams` carries a ``features`` record
array whose dtype names the features compiled in (:func:`of`: those some drive of the arrays
runs, completed to their :data:`GROUPS`). A block wrapped by :func:`compiled` is typed only
where its feature is in that dtype; elsewhere a light stand-in of the same signature runs,
which returns what the block returns when its branch is not taken. So the results are the
same bit for bit, and numba compiles one loop per set of features, as it compiles one per
estimator.

The predicates are written on record fields by subscript with ``&``, ``|`` and comparisons:
the kernels call them on a record, :func:`used` on the record arrays of a batch (numpy
elementwise), so the decision to compile a block and the branch that runs it are one code.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Mapping

import numpy as np
from numba import types
from numba.extending import overload

from imdrive.kernels.inverter import INV_SWITCHING
from imdrive.kernels.jit import IMPL, njit
from imdrive.kernels.records import b1, record_dtype


@njit(cache=True, inline="always")
def tracks_r2(pk):
    """The R2 tracking runs: the compensator, its detection or its injection (``pk``: the
    compensator's params)."""
    return pk["enabled"] | pk["det"] | (pk["inj_amp"] != 0.0)


@njit(cache=True, inline="always")
def switching_bridge(pinv):
    """The plant is fed by the switching bridge (``pinv``: the inverter's params), not the
    average inverter model."""
    return pinv["model"] == INV_SWITCHING


@njit(cache=True, inline="always")
def standstill_r1(pc):
    """The standstill R1 test runs while the rotor magnetises (``pc``: the controller's)."""
    return pc["R1_dc"]


@njit(cache=True)
def has_feedforward(pc):
    """Whether the controller compensates the inverter's voltage error (dead-time sign model
    or the identified table; ``pc``: the controller's params). Also
    ``kernels.ifoc.has_feedforward``."""
    return (pc["dtc_u"] > 0.0) | (pc["ie_n"] > 0)


@njit(cache=True, inline="always")
def phase_sensors(psen):
    """The current is measured by per-phase sensors (gains, offsets, noise, ADC), not only an
    offset vector (``psen``: the sensors' params)."""
    return psen["phase_model"]


#: Each feature: its predicate and the :class:`~imdrive.kernels.engine.DriveParams` field it
#: reads.
FEATURES = {
    "r2_tracking": (tracks_r2, "comp"),
    "switching_bridge": (switching_bridge, "inverter"),
    "standstill_r1": (standstill_r1, "control"),
    "inverter_compensation": (has_feedforward, "control"),
    "phase_sensors": (phase_sensors, "sensor"),
}


def features_dtype(names) -> np.dtype:
    """The ``features`` record of a drive that compiles ``names`` (in :data:`FEATURES`'
    order), after a first field named by the whole set (``set__`` and the names).

    That first field keeps two sets apart: numba passes a record where a record of a prefix
    of its fields is expected (width subtyping), so a function compiled for the lean set
    could run for a drive with more blocks.
    """
    return _features_dtype(frozenset(names))


@functools.cache
def _features_dtype(names: frozenset) -> np.dtype:  # one dtype per set: a batch makes many
    unknown = set(names) - set(FEATURES)
    if unknown:
        raise KeyError(f"unknown features {sorted(unknown)}: known are {list(FEATURES)}")
    ordered = [n for n in FEATURES if n in names]
    first = "set__" + "__".join(ordered or ["none"])  # an identifier: numpy's buffers want one
    return record_dtype([(first, b1)] + [(n, b1) for n in ordered])


#: Every feature compiled: what a drive whose ``features`` is ``None`` runs.
EVERY = features_dtype(FEATURES)


#: What a drive compiles together: one feature of a group compiles the group. Each
#: combination of features is an engine of its own for every estimator and entry point, and
#: the five apart made the test suite compile 41 engines and run 6 min 37 s instead of 3 min 7 s
#: (2026-11-30); the R2 tracking and the realistic inverter and sensors are what a scenario
#: adds, so two groups keep a drive with neither lean (a cold ``imdrive run sensorless``
#: 22.3 -> 11.8-12.8 s) at four engines per estimator.
GROUPS = (
    ("r2_tracking", "standstill_r1"),
    ("switching_bridge", "inverter_compensation", "phase_sensors"),
)


def used(records) -> tuple[str, ...]:
    """The features some drive of ``records`` runs, completed to their :data:`GROUPS`.
    ``records``: a ``DriveParams`` or a mapping of its field names to record arrays."""
    get = records.__getitem__ if isinstance(records, Mapping) else records.__getattribute__
    runs = {name for name, (pred, field) in FEATURES.items() if np.any(pred.py_func(get(field)))}
    return tuple(name for group in GROUPS if runs & set(group) for name in group)


def of(records, names=None) -> np.ndarray:
    """The ``features`` array, one row per drive, that compiles ``names`` (default: those
    the drives of ``records`` run, :func:`used`)."""
    names = used(records) if names is None else names
    get = records.__getitem__ if isinstance(records, Mapping) else records.__getattribute__
    return np.ones(get("sim").shape[0], dtype=features_dtype(names))


def has(features, name: str) -> bool:
    """Whether the ``features`` array (or ``None``: every one) compiles ``name``."""
    return features is None or name in features.dtype.names


def row(features, i):
    """Drive ``i``'s ``features`` record (``None`` stays ``None``: every feature)."""
    raise NotImplementedError("compiled only")


@overload(row, inline="always", jit_options=IMPL)
def _row(features, i):
    if isinstance(features, types.NoneType):
        return lambda features, i: None
    return lambda features, i: features[i]


def compiled(feature: str, off):
    """Decorator: the block runs where ``feature`` is compiled into the drive, ``off`` (a
    compiled function of the same arguments) elsewhere, and the block is then never typed.

    The wrapped block takes the drive's ``features`` record (:func:`row`) as a first argument
    ``feat``: ``block(feat, *args)``. ``off`` returns what the block returns when the branch
    that calls it is not taken (it is called only there, through the feature's predicate).

    The block runs inside a compiled function of its own, named after it (``bridge_period__on``),
    which the loop calls; the stand-in is inlined (numba's cost model, ``off_inlined``). They
    were both inlined until 2026-12-02: numba compiles an inlined implementation once to type
    the call and again inside the caller, so the realistic drive's loop lowered every block
    twice (the first ``imdrive bench-estimators`` after a warm run: +12.0, +11.5, +12.6, +12.5
    s over warm against +14.1, +12.8, +13.7, +14.1 s in four alternated pairs; the kernel's
    time per period unchanged). A function that takes ``feat`` may be compiled for several
    features records since numba names compiled functions by their argument types' content
    (:func:`imdrive.kernels.jit._content_mangler`): before, two variants of ``foc_step`` that
    differed only in the features record got one symbol name in processes that compiled in
    the same order, and a process that loaded both from the cache ran one for the other (9
    tests of the clean-clone CI, 2026-11-30).
    """
    if feature not in FEATURES:
        raise KeyError(f"unknown feature {feature!r}: known are {list(FEATURES)}")

    def wrap(block):
        # the block's own arguments, spelled out: numba inlines no call through ``*args``
        names = ", ".join(inspect.signature(block.py_func).parameters)
        src = f"def gated(feat, {names}):\n    return run({names})\n"
        stub = _define(src, run=block)  # called from Python: the block, whatever ``feat``
        stub.__name__ = stub.__qualname__ = block.__name__
        stub.__doc__ = block.__doc__
        stub.__module__ = block.__module__
        impl_on, impl_off = _define(src, run=block), _define(src, run=off)
        for impl, kind in ((impl_on, "on"), (impl_off, "off")):
            impl.__module__ = block.__module__
            impl.__qualname__ = f"{block.__name__}__{kind}"

        def choose(feat):  # at typing: the block where the drive compiles the feature
            # None (or a block's argument left out): every block
            on = isinstance(feat, (types.NoneType, types.Omitted)) or feature in feat.fields
            return impl_on if on else impl_off

        def off_inlined(expr, caller, callee):  # numba's cost model: inline the stand-in only
            return callee.func_ir.func_id.func is impl_off

        overload(stub, inline=off_inlined, jit_options=IMPL)(
            _define(src, run=choose, feat_only=True)
        )
        return stub

    return wrap


def _define(src: str, feat_only=False, **names):
    """The function ``gated`` that ``src`` defines, its globals ``names`` (``feat_only``:
    ``run`` is called with ``feat`` alone: the typing function of the overload)."""
    if feat_only:
        src = src.splitlines()[0] + "\n    return run(feat)\n"
    scope = dict(names)
    exec(src, scope)  # noqa: S102  (our own source, spelled from a signature)
    return scope["gated"]
