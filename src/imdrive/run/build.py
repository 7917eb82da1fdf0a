"""From a :class:`~imdrive.config.scenario.Scenario` to the records the kernels run on.

Each block's record is filled by field name (:func:`imdrive.kernels.records.new_record`, which
refuses an unknown name) from the configuration and the gain design; the result is one
:class:`~imdrive.kernels.engine.DriveParams` and the initial
:class:`~imdrive.kernels.engine.DriveState`, every array of shape ``(1,)``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from imdrive.config.perunit import resolve
from imdrive.config.r2_laws import plugin_law
from imdrive.config.scenario import Scenario
from imdrive.config.sequence import sequence
from imdrive.errors import ConfigError
from imdrive.kernels import features
from imdrive.kernels.engine import DriveParams, DriveState, log_dtype
from imdrive.run import blocks
from imdrive.run.blocks import RPM, saturation_curve  # noqa: F401  (re-exported: old path)
from imdrive.run.compensator_blocks import plugin_law_kernel
from imdrive.run.estimators import EstimatorContext, build_estimator, estimator_of

MAX_LOG_BYTES = 2 * 2**30  # a log larger than this is refused before anything runs


def check_log_size(sc: Scenario, log: np.dtype | None = None, n_steps: int | None = None) -> None:
    """Refuse a scenario whose log would not fit in :data:`MAX_LOG_BYTES`.

    ``log`` is the drive's log dtype (default: that of the scenario's estimator), ``n_steps``
    its number of control periods (default: the run's, the premagnetisation's delay included,
    :func:`imdrive.config.sequence.sequence`).
    """
    sim = sc.simulation
    if log is None:
        log = log_dtype(estimator_of(sc).kernel, plugin_law_kernel(sc))
    n_steps = sequence(sc).n_steps(sim.Ts_s) if n_steps is None else n_steps
    log_bytes = (n_steps // sim.log_every + 1) * log.itemsize
    if log_bytes > MAX_LOG_BYTES:
        raise ConfigError(
            "simulation.log_every",
            f"the log would take {log_bytes / 2**30:.1f} GiB (limit "
            f"{MAX_LOG_BYTES / 2**30:.0f} GiB): raise simulation.log_every",
        )


@dataclass
class DriveArrays:
    """Everything the compiled loop needs for one drive.

    Attributes
    ----------
    params : DriveParams
        Constant inputs, every array of shape ``(1,)`` (profiles and table with a leading 1).
    state0 : DriveState
        Initial state; :func:`copy_state` before running, the kernels update it in place.
    n_steps, log_every : int
    derived : dict
        Derived quantities reported in ``summary.json`` (gains, limits, ...).
    sources : dict
        For a derived quantity or record field, the setting it comes from (to name it when
        its value is not finite).
    log : numpy.dtype
        The drive's log record: every block's fields and its estimator's own.
    log_units : dict
        ``{field: (unit, scale)}`` of the estimator's own log fields (for the result's columns).
    """

    params: DriveParams
    state0: DriveState
    n_steps: int
    log_every: int
    derived: dict
    sources: dict = field(default_factory=dict)
    log: np.dtype = field(default_factory=lambda: log_dtype("mras"))
    log_units: dict | None = None

    @property
    def Ts(self) -> float:
        return float(self.params.sim["Ts"][0])


def copy_state(state: DriveState) -> DriveState:
    """A deep copy of a drive state (the kernels write into the arrays)."""
    return DriveState(*(a.copy() for a in state))


#: The setting a derived quantity (summary.json "derived", or a record field) comes from, to
#: name it when the derived value overflows.
DERIVED_SOURCE = {
    "current_kp": "control.current_bandwidth_Hz",
    "current_ki": "control.current_bandwidth_Hz",
    "speed_kp": "control.speed_bandwidth_Hz",
    "speed_ki": "control.speed_bandwidth_Hz",
    "flux_ref_Wb": "control.flux_ref_Wb",
    "torque_constant_Nm_per_A": "control.flux_ref_Wb",
    "current_limit_A": "control.current_limit_A",
    "divergence_current_A": "simulation.divergence_current_A",
    "rated_current_A": "machine.rated_power_W",
    "sigma": "machine.M_H",
    "T2_s": "machine.R2_ohm",
    "v_max_V": "inverter.Vdc_V",
    "R2_hat_min_ohm": "compensator.R2_min_ohm",
    "R2_hat_max_ohm": "compensator.R2_max_ohm",
    "sim.w_lim": "simulation.divergence_speed_rpm",
    "sim.i_lim": "simulation.divergence_current_A",
    "control.v_max": "inverter.Vdc_V",
    "control.dtc_u": "control.dead_time_compensation_s",
    "plant.k_visc": "load.viscous_Nms",
    "plant.k_fan": "load.fan_Nms2",
    "sensor.adc_range": "sensor.adc_range_A",
    "comp.inj_amp": "injection.amplitude_A",
    "prof_v": "scenario",
}
_GAIN_OVERRIDE = {
    "current_kp": "control.current_kp",
    "current_ki": "control.current_ki",
    "speed_kp": "control.speed_kp",
    "speed_ki": "control.speed_ki",
}


def _not_finite(name: str, value, sc: Scenario, sources=DERIVED_SOURCE) -> ConfigError:
    key = sources.get(name, "scenario")
    if name in _GAIN_OVERRIDE:
        section, setting = _GAIN_OVERRIDE[name].split(".")
        if getattr(getattr(sc, section), setting) is not None:
            key = _GAIN_OVERRIDE[name]
    return ConfigError(
        key,
        f"gives a derived quantity {name} = {value} that is not a finite number (an overflow "
        "of extreme values): bring the settings it is computed from into a physical range",
    )


@functools.lru_cache(maxsize=512)
def _float_bytes(dtype: np.dtype) -> np.ndarray | None:
    """Byte offsets of every float64 / complex128 value in a record of ``dtype`` (None if a
    float field has another width: the caller then checks field by field)."""
    idx: list[int] = []
    for name in dtype.names:
        sub, offset = dtype.fields[name][:2]
        base = sub.subdtype[0] if sub.subdtype else sub
        if base.kind not in "fc":
            continue
        if base.kind == "f" and base.itemsize != 8 or base.kind == "c" and base.itemsize != 16:
            return None
        idx.extend(range(offset, offset + sub.itemsize))
    return np.asarray(idx, dtype=np.intp)


def _all_finite(arr: np.ndarray) -> bool:
    """Whether every float and complex value of ``arr`` (records or a plain array) is finite."""
    if arr.dtype.names is None:
        return arr.dtype.kind not in "fc" or bool(np.isfinite(arr).all())
    idx = _float_bytes(arr.dtype)
    if idx is None:
        return False
    if not idx.size or not arr.size:
        return True
    raw = np.ascontiguousarray(arr).reshape(-1).view(np.uint8).reshape(arr.size, -1)
    return bool(np.isfinite(np.ascontiguousarray(raw[:, idx]).view(np.float64)).all())


@functools.lru_cache(maxsize=512)
def _joint_float_bytes(layout: tuple) -> np.ndarray | None:
    """Byte offsets of every float64 / complex128 value in the arrays of ``layout``, a tuple of
    ``(dtype, size)`` laid end to end (None if some float has another width)."""
    idx: list[np.ndarray] = []
    start = 0
    for dtype, size in layout:
        if dtype.names is None:
            if dtype.kind in "fc" and dtype.itemsize not in (8, 16):
                return None
            one = np.arange(dtype.itemsize if dtype.kind in "fc" else 0, dtype=np.intp)
        else:
            one = _float_bytes(dtype)
            if one is None:
                return None
        rows = start + dtype.itemsize * np.arange(size, dtype=np.intp)
        idx.append((rows[:, None] + one[None, :]).ravel())
        start += dtype.itemsize * size
    return np.concatenate(idx) if idx else np.zeros(0, dtype=np.intp)


def _all_finite_joint(arrs) -> bool:
    """:func:`_all_finite` of every array of ``arrs`` at once: one gather of their bytes laid
    end to end (a drive has about 20 records, and one check each was a fifth of the time
    ``build_arrays`` took)."""
    idx = _joint_float_bytes(tuple((a.dtype, a.size) for a in arrs))
    if idx is None:
        return all(_all_finite(a) for a in arrs)
    raw = np.frombuffer(b"".join(np.ascontiguousarray(a).tobytes() for a in arrs), np.uint8)
    return bool(np.isfinite(raw[idx].view(np.float64)).all())


def check_finite(arrays: DriveArrays, sc: Scenario) -> None:
    """Refuse arrays holding a non-finite number: every derived quantity must be finite.

    Checks the reported derived quantities, then every float and complex field of the
    parameter and initial-state records and the profiles. Raises
    :class:`~imdrive.errors.ConfigError` naming the setting the first bad value comes from.
    """
    for name, value in arrays.derived.items():
        if not math.isfinite(float(value)):
            raise _not_finite(name, value, sc, arrays.sources or DERIVED_SOURCE)
    if _all_finite_joint([rec for records in (arrays.params, arrays.state0) for rec in records]):
        return  # the usual case, in one pass (the loop below names a bad field)
    for records in (arrays.params, arrays.state0):
        for rec_name, rec in zip(records._fields, records, strict=True):
            fields_ = rec.dtype.names or (None,)
            for f in fields_:
                arr = rec[f] if f is not None else rec
                if arr.dtype.kind in "fc" and not np.all(np.isfinite(arr)):
                    key = f"{rec_name}.{f}" if f is not None else rec_name
                    bad = arr[~np.isfinite(arr)].ravel()[0]
                    raise _not_finite(key, bad, sc, arrays.sources or DERIVED_SOURCE)


def build_arrays(sc: Scenario) -> DriveArrays:
    """Fill every block's parameter and state records from the scenario.

    Every derived quantity is checked: a scenario whose derived parameters overflow (to
    infinity, NaN, or beyond a 64-bit integer) raises :class:`~imdrive.errors.ConfigError`
    naming the setting, before anything runs (:func:`check_finite`).
    """
    try:
        arrays = _build_arrays(sc)
    except ConfigError:
        raise
    except (ArithmeticError, ValueError) as exc:  # overflow of a float or of an int64 field
        raise ConfigError(
            "scenario",
            f"its derived parameters cannot be computed ({type(exc).__name__}: {exc}): some "
            "values are far outside a physical range",
        ) from None
    check_finite(arrays, sc)
    return arrays


def _build_arrays(sc: Scenario) -> DriveArrays:
    """Every block's records from its own builder (:mod:`imdrive.run.blocks`)."""
    est = estimator_of(sc)  # once: its kernel gives the log, its settings the gains and units
    law = plugin_law_kernel(sc)  # a plug-in R2 law's log fields follow the estimator's
    log = log_dtype(est.kernel, law)
    n_steps = sequence(sc).n_steps(sc.simulation.Ts_s)  # the premagnetisation's delay too
    check_log_size(sc, log, n_steps)
    D = resolve(sc)  # every machine-dependent value, once
    m = sc.machine
    model, mh = blocks.model_fields(sc, D)
    psi0 = blocks.initial_flux(sc, D)
    ctx = EstimatorContext(
        scenario=sc,
        Ts=sc.simulation.Ts_s,
        psi0=psi0,
        n_p=m.pole_pairs,
        J=m.J_kgm2,
        **mh,
    )
    est, est_params, est_state, er = build_estimator(sc, ctx, est)
    log_units = dict(est.log_units)
    if law is not None:
        log_units.update(plugin_law(law.name).law_log_units)
    rec, gains, comp_derived = blocks.drive_records(sc, D, model, mh, psi0)
    gains.update(er.derived)
    prof_t, prof_v, prof_n = blocks.profile_arrays(sc, D)
    records = {"est": est_params, **{k: rec[k] for k in ("sim", "plant", "inverter", "sensor")}}
    records.update(control=rec["control"], comp=rec["comp"])
    params = DriveParams(
        **records,
        prof_t=prof_t[None],
        prof_v=prof_v[None],
        prof_n=prof_n[None],
        tables=np.ascontiguousarray(blocks.fuzzy_lookup_table(sc)[None]),
        table_idx=np.zeros(1, dtype=np.int64),
        features=features.of(records),  # compile only the blocks this drive runs
    )
    state0 = blocks.initial_state(sc, D, rec["model"], est_state, rec["comp_state"])

    derived = dict(gains)
    derived.update(blocks.drive_derived(sc, D, psi0, mh))
    derived.update(comp_derived)
    return DriveArrays(
        params=params,
        state0=state0,
        n_steps=n_steps,
        log_every=sc.simulation.log_every,
        derived=derived,
        sources={**DERIVED_SOURCE, **er.sources},
        log=log,
        log_units=log_units,
    )
