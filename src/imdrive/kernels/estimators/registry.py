"""Speed estimators as plug-ins: one step contract, one registry, dispatch by record type.

An estimator is a numba-compiled block with its own parameter and state record dtypes. It is
registered once (:func:`register_kernel`), and the engine calls it through three generic
functions, :func:`estimator_step`, :func:`estimator_log` and :func:`estimator_finite`. Numba
resolves each call at compile time from the *type* of the state record it receives: the drive
of an estimator carries that estimator's records (``DriveParams.est``, ``DriveState.est``), so
the loop is compiled once per estimator and holds no branch per estimator (a batch of several
runs them in one loop on union records, :mod:`.union`). The registry maps
the state dtype to the functions, which is why every registered state and parameter dtype is made
unique (a tag field, below).

The contract
------------
``step(p, model, s, inp) -> (w_r_hat, e_dq0)``
    ``p``: the estimator's parameter record; ``model``: the controller's machine model
    (:data:`imdrive.kernels.model.MODEL_STATE`; an estimator may adapt ``R1_hat``/``R2_hat``
    in it); ``s``: its state record (updated in place); ``inp``: an :class:`EstimatorInput`
    (the fields of :data:`ESTIMATOR_INPUT`, read-only: the last period's voltage, the last
    two current samples, the controller's angle, frequency and references, the R2
    compensator's injected current, whether the drive's standstill R1 test has just set
    ``R1_hat``; a step written for an ``ESTIMATOR_INPUT`` record reads
    the named tuple unchanged). Returns the electrical
    speed estimate, rad/s, and the rotor-flux error in the controller's frame, Wb (complex;
    ``0j`` if the estimator has none: the R2 compensator then sees no signal).
``log(row, p, s, n_p)`` (optional)
    Writes the estimator's own ``log_fields`` into the log record ``row``.
``finite(s) -> bool`` (optional)
    Whether the estimator's internal state is finite (a NaN there is a divergence); without it
    only the returned values are checked.
``flux(s) -> complex`` (optional)
    The estimator's rotor-flux estimate after its step, stationary frame, Wb, for an
    estimator that observes the flux (the AFO, the EKF): the drive orients its frame on it
    above 0.1 of the rated stator frequency (direct field orientation,
    :mod:`imdrive.kernels.ifoc`); without it the frame integrates the slip (indirect).
``flux_magnitude(s) -> float`` (optional)
    The magnitude of a rotor-flux estimate that an R̂2 error does not move, Wb, for the
    controller's magnetising curve on an encoder drive (``control.speed_feedback =
    "measured"``, the MRAS beside): the MRAS's adjustable-model flux, whose speed the MRAS
    adapts until its angle is the voltage model's, so that its magnitude is the machine's
    whatever R̂2. Without it the controller evaluates ``M̂`` at its own flux model's, which
    an R̂2 error detunes on an encoder drive (:mod:`imdrive.kernels.ifoc`).
``reduced`` (optional, a :class:`ReducedState`)
    The estimator's states in the stability maps' reduced drive state
    (:mod:`imdrive.kernels.linearise`): their names, scales, the two functions that write them
    into the state vector (rotated into the controller's frame) and back, and their continuous
    steady state, Newton's start. Without it the maps refuse the estimator in one line.

Caching
-------
The engine inlines the estimator, so its cached machine code must change whenever the
estimator's source does. A kernel module's cache folder is named after a hash of its sources
and of every kernel module it imports, and this module's after every module that imports it
(:mod:`imdrive._cache`); an estimator defined outside the package gets a tag field whose
name carries a hash of its module's name and source file, so an edited user estimator is a
new record type and is compiled afresh, never taken stale from the cache (and the same text
loaded as another module does not find a loop compiled against the first).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numba import types
from numba.extending import overload
from numba.np.numpy_support import as_dtype

from imdrive.kernels.jit import CACHED_IMPL
from imdrive.kernels.plugin_registry import Registry, source_tag, tagged
from imdrive.kernels.records import b1, c16, f8, record_dtype

#: The generic entry points below compile the step of whichever estimator registered here, so
#: their cache follows every module that imports this one (:mod:`imdrive._cache`).
_CACHE_FOLLOWS_IMPORTERS = True

#: What the engine hands an estimator each period (SI units; space vectors complex, in the
#: stationary frame ``_ab`` or the controller's frame ``_dq``).
ESTIMATOR_INPUT = record_dtype(
    [
        ("v_ab", c16),  # voltage the controller commanded over the last period, V
        ("i_prev_ab", c16),  # current sample at the start of the last period, A
        ("i_ab", c16),  # current sample now, A
        ("theta_e", f8),  # the controller's d-axis angle at this sample, rad
        ("w_e", f8),  # the controller's stator (field) frequency, electrical rad/s
        ("i_ref_dq", c16),  # the current references of the last period, A
        ("w_ref", f8),  # speed reference, mechanical rad/s
        ("i_inj", f8),  # the R2 compensator's injected d-axis current this period, A
        ("hold_R1", b1),  # R1 adaptation held (the compensator's gating asks for it)
        ("Ts", f8),  # control period, s
        ("t", f8),  # time of this sample, s
        # the drive's standstill R1 test set R1_hat at the last sample: an estimator whose
        # models integrated through the test with the old R1_hat restarts them
        # (kernels/r1_standstill.py)
        ("restart", b1),
    ]
)


class EstimatorInput(NamedTuple):
    """What the engine hands an estimator each period: the fields of :data:`ESTIMATOR_INPUT`,
    in its order, as a named tuple (a value numba keeps in registers; a step reads
    ``inp.v_ab`` etc. from either)."""

    v_ab: complex
    i_prev_ab: complex
    i_ab: complex
    theta_e: float
    w_e: float
    i_ref_dq: complex
    w_ref: float
    i_inj: float
    hold_R1: bool
    Ts: float
    t: float
    restart: bool


@dataclass(frozen=True)
class ReducedState:
    """An estimator's states in the stability maps' reduced drive state.

    The map (:mod:`imdrive.kernels.linearise`) runs the drive one control period from a state
    vector in the controller's frame; its first entries are the plant's and the controller's,
    then the estimator's, written by ``reduce`` and read back by ``restore``. Every state that
    carries over from one period to the next must be there (a missing one is held at a stale
    value and the Jacobian is wrong); nothing else should be (a value that never changes is a
    neutral eigenvalue 1, which reads as marginal stability).

    Attributes
    ----------
    names : tuple of str
        Its states' names (space vectors as two entries, ``_d``/``_q``: the controller's
        frame), SI units.
    scale : tuple of float
        Each state's typical magnitude (finite-difference steps, the fixed point's residual).
    reduce : numba dispatcher
        ``reduce(p, s, c, z, k)``: writes the states of parameter and state records ``p``,
        ``s`` into ``z[k:k + len(names)]``, stationary-frame vectors rotated by ``e^{-j th}``
        with ``c = (cos th, sin th)`` (:func:`imdrive.kernels.estimators.common.to_frame`).
    restore : numba dispatcher
        ``restore(z, k, s)``: writes them back into ``s`` (the frame angle is then 0: the
        stationary frame is the controller's).
    steady : callable
        ``steady(c, p, I, w_e, w_r_hat) -> ndarray (n, len(names))``: the states in the
        continuous steady state of the loop with imposed currents (Newton's start; Newton then
        finds the discrete loop's fixed point), from the model's constants ``c``
        (:func:`imdrive.run.linear.model_coefficients`), the parameter record ``p`` (row 0),
        the stator current ``I`` in the controller's frame, A, the stator frequency ``w_e``
        and the speed estimate ``w_r_hat``, electrical rad/s (arrays of ``n`` points).
    speed : str
        The name of the speed estimate among ``names`` (the maps' ``speed_est_rpm`` output).
    """

    names: tuple[str, ...]
    scale: tuple[float, ...]
    reduce: object
    restore: object
    steady: object
    speed: str = "w_r_hat"

    def __post_init__(self):
        if len(self.names) != len(self.scale) or self.speed not in self.names:
            raise ValueError("ReducedState: one scale per name, and the speed among the names")


@dataclass(frozen=True)
class EstimatorKernel:
    """The compiled half of an estimator: its records and its numba functions.

    Attributes
    ----------
    name : str
        The value of ``control.speed_feedback`` that selects it.
    params, state : numpy.dtype
        Its parameter and state record dtypes, as registered: each with the tag field.
    step : numba dispatcher
        ``step(p, model, s, inp) -> (w_r_hat, e_dq0)`` (module docstring).
    log_fields : tuple of str
        Its own log fields (float64), written by ``log``; their units are declared with the
        settings half (:class:`imdrive.estimators.Estimator`).
    log, finite : numba dispatcher or None
        Optional (module docstring).
    flux : numba dispatcher or None
        Optional: its rotor-flux estimate, which the drive orients on (module docstring).
    flux_magnitude : numba dispatcher or None
        Optional: an R̂2-independent rotor-flux magnitude for the magnetising curve on an
        encoder drive (module docstring).
    reduced : ReducedState or None
        Optional: its states in the stability maps' reduced drive state (module docstring).
    """

    name: str
    params: np.dtype
    state: np.dtype
    step: object
    log_fields: tuple[str, ...] = ()
    log: object = None
    finite: object = None
    flux: object = None
    reduced: ReducedState | None = None
    flux_magnitude: object = None
    source: str = field(default="", compare=False)

    @property
    def reduced_state(self) -> bool:
        """Whether the stability maps' reduced drive state carries it (``reduced`` is set)."""
        return self.reduced is not None


_REGISTRY = Registry("estimator")
_BY_STATE = _REGISTRY.by_record
_source_tag = source_tag
_tagged = tagged


def register_kernel(
    name: str,
    params: np.dtype,
    state: np.dtype,
    step,
    log_fields=(),
    log=None,
    finite=None,
    reduced_state: bool = False,
    flux=None,
    reduced: ReducedState | None = None,
    flux_magnitude=None,
) -> EstimatorKernel:
    """Register an estimator's compiled half under ``name`` and return it.

    Parameters
    ----------
    name : str
        The ``control.speed_feedback`` value that selects it.
    params, state : numpy.dtype
        Record dtypes (fields by name; see :mod:`imdrive.kernels.records`).
    step : numba dispatcher
        ``step(p, model, s, inp) -> (w_r_hat, e_dq0)``.
    log_fields : sequence of str
        Log fields it writes (float64).
    log, finite, flux, flux_magnitude : numba dispatcher, optional
        See the module docstring.
    reduced_state : bool
        Deprecated, no effect: the maps carry an estimator that gives ``reduced``.
    reduced : ReducedState, optional
        Its states in the stability maps' reduced drive state (module docstring).

    Returns
    -------
    EstimatorKernel
        With ``params`` and ``state`` extended by a tag field that makes them unique (module
        docstring).
        Registering the same name again replaces the entry (a re-imported user module).
    """
    if reduced_state and reduced is None:
        warnings.warn(
            "register_kernel(reduced_state=True) has no effect: give the estimator's states "
            "to the stability maps with reduced=ReducedState(...)",
            DeprecationWarning,
            stacklevel=2,
        )
    tag = _source_tag(step)
    tagged = _tagged(np.dtype(state), name, tag)
    kernel = EstimatorKernel(
        name=name,
        params=_tagged(np.dtype(params), name, tag),
        state=tagged,
        step=step,
        log_fields=tuple(log_fields),
        log=log,
        finite=finite,
        flux=flux,
        reduced=reduced,
        flux_magnitude=flux_magnitude,
        source=tag,
    )
    return _REGISTRY.add(kernel)


def kernel(name: str) -> EstimatorKernel:
    """The registered estimator ``name`` (``KeyError`` naming the registered ones)."""
    return _REGISTRY[name]


def kernel_names() -> tuple[str, ...]:
    """Names of every registered estimator, in registration order."""
    return _REGISTRY.names()


def kernel_of_state(dtype: np.dtype) -> EstimatorKernel:
    """The estimator whose (tagged) state or parameter dtype is ``dtype``."""
    return _BY_STATE[np.dtype(dtype)]


def _lookup(s) -> EstimatorKernel | None:
    if not isinstance(s, types.Record):
        return None
    return _BY_STATE.get(as_dtype(s))


# --- generic entry points, resolved by numba from the state record's type -------------------


def estimator_step(p, model, s, inp):
    """Advance the estimator whose state is ``s`` by one period (compiled code only)."""
    raise NotImplementedError("estimator_step is called from compiled code only")


def estimator_log(row, p, s, n_p):
    """Write the estimator's own log fields (compiled code only)."""
    raise NotImplementedError("estimator_log is called from compiled code only")


def estimator_finite(s):
    """Whether the estimator's state is finite (compiled code only)."""
    raise NotImplementedError("estimator_finite is called from compiled code only")


def estimator_flux(s):
    """The estimator's rotor-flux estimate, stationary frame, Wb (``0j``: it has none;
    compiled code only)."""
    raise NotImplementedError("estimator_flux is called from compiled code only")


@overload(estimator_step, inline="always", jit_options=CACHED_IMPL)
def _estimator_step(p, model, s, inp):
    k = _lookup(s)
    if k is None:
        return None
    step = k.step

    def impl(p, model, s, inp):
        return step(p, model, s, inp)

    return impl


@overload(estimator_log, inline="always", jit_options=CACHED_IMPL)
def _estimator_log(row, p, s, n_p):
    k = _lookup(s)
    if k is None:
        return None
    fields = getattr(row, "fields", None)
    if k.log is None or (fields is not None and not set(k.log_fields) <= set(fields)):
        # no log function, or a log record without its fields: the stability maps' engine
        # logs nothing and runs on the package's record (kernels/linearise.py)

        def nothing(row, p, s, n_p):
            pass

        return nothing
    log = k.log

    def impl(row, p, s, n_p):
        log(row, p, s, n_p)

    return impl


@overload(estimator_finite, inline="always", jit_options=CACHED_IMPL)
def _estimator_finite(s):
    k = _lookup(s)
    if k is None:
        return None
    if k.finite is None:
        return lambda s: True
    finite = k.finite
    return lambda s: finite(s)


def estimator_flux_magnitude(s):
    """The estimator's R̂2-independent rotor-flux magnitude, Wb (``0.0``: it has none;
    compiled code only)."""
    raise NotImplementedError("estimator_flux_magnitude is called from compiled code only")


@overload(estimator_flux_magnitude, inline="always", jit_options=CACHED_IMPL)
def _estimator_flux_magnitude(s):
    k = _lookup(s)
    if k is None:
        return None
    if k.flux_magnitude is None:
        return lambda s: 0.0
    mag = k.flux_magnitude
    return lambda s: mag(s)


@overload(estimator_flux, inline="always", jit_options=CACHED_IMPL)
def _estimator_flux(s):
    k = _lookup(s)
    if k is None:
        return None
    if k.flux is None:
        return lambda s: 0j
    flux = k.flux
    return lambda s: flux(s)
