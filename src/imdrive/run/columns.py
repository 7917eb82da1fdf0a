"""The exported columns of a run: each log field's unit and scale (:data:`LOG_UNITS`), the
columns of an open-loop and of a vector-controlled run, and the unit a column's name ends with.

The exported column is ``f"{field}_{unit}"`` holding ``log[field] * scale`` (``speed`` ->
``speed_rpm``); :mod:`imdrive.run.result` re-exports these names.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

RPM = 2.0 * math.pi / 60.0
SQ3_2 = math.sqrt(3.0) / 2.0

#: The units table: log field (SI, see each block's LOG_FIELDS) -> (unit, scale). The exported
#: column is ``f"{field}_{unit}"`` holding ``log[field] * scale``. ``v_alpha_V``/``v_beta_V``
#: are the period-average voltage applied at the terminals over [t_k, t_k + Ts) (the bridge's
#: true average with the switching model, dead time included; the commanded one at the last
#: sample, which has no period after it); ``v_ref_*`` the controller's reference at sample k;
#: ``i_*_meas_A`` what the current sensors report, ``i_alpha_A``/``i_beta_A`` the true current.
LOG_UNITS = {
    "time": ("s", 1.0),
    "speed": ("rpm", 1.0 / RPM),
    "torque": ("Nm", 1.0),
    "load_torque": ("Nm", 1.0),
    "i_alpha": ("A", 1.0),
    "i_beta": ("A", 1.0),
    "psi_r_alpha": ("Wb", 1.0),
    "psi_r_beta": ("Wb", 1.0),
    "R1": ("ohm", 1.0),
    "R2": ("ohm", 1.0),
    "flux": ("Wb", 1.0),
    "theta1": ("C", 1.0),
    "theta2": ("C", 1.0),
    "v_alpha": ("V", 1.0),
    "v_beta": ("V", 1.0),
    "v_ref_alpha": ("V", 1.0),
    "v_ref_beta": ("V", 1.0),
    "i_alpha_meas": ("A", 1.0),
    "i_beta_meas": ("A", 1.0),
    "speed_ref": ("rpm", 1.0 / RPM),
    "id_ref": ("A", 1.0),
    "iq_ref": ("A", 1.0),
    "i_d": ("A", 1.0),
    "i_q": ("A", 1.0),
    "theta_e": ("rad", 1.0),
    "speed_est": ("rpm", 1.0 / RPM),
    "e_d0": ("Wb", 1.0),
    "e_q0": ("Wb", 1.0),
    "lam_v_alpha": ("Wb", 1.0),
    "lam_v_beta": ("Wb", 1.0),
    "lam_i_alpha": ("Wb", 1.0),
    "lam_i_beta": ("Wb", 1.0),
    "R2_hat": ("ohm", 1.0),
    "R1_hat": ("ohm", 1.0),
    "e_d0_demod": ("Wb", 1.0),
    "comp_frozen": ("flags", 1.0),
    "inj_freq": ("Hz", 1.0),
    "comp_live": ("flag", 1.0),
    "R1_id_status": ("code", 1.0),
    "rotor_rise": ("K", 1.0),
}
# column -> (log field, scale) for every column taken straight from the log
_DIRECT = {f"{f}_{u}": (f, k) for f, (u, k) in LOG_UNITS.items()}
_DIRECT["w_m_rad_s"] = ("speed", 1.0)  # the speed in SI as well

OPEN_LOOP_COLUMNS = (
    "time_s speed_rpm w_m_rad_s torque_Nm load_torque_Nm i_a_A i_b_A i_c_A i_alpha_A i_beta_A "
    "i_alpha_meas_A i_beta_meas_A psi_r_alpha_Wb psi_r_beta_Wb v_alpha_V v_beta_V "
    "v_ref_alpha_V v_ref_beta_V R1_ohm R2_ohm flux_Wb theta1_C theta2_C"
).split()
VECTOR_COLUMNS = (
    OPEN_LOOP_COLUMNS
    + (
        "speed_ref_rpm speed_est_rpm id_ref_A iq_ref_A i_d_A i_q_A R2_hat_ohm e_d0_Wb e_q0_Wb "
        "theta_e_rad lam_v_alpha_Wb lam_v_beta_Wb lam_i_alpha_Wb lam_i_beta_Wb e_d0_demod_Wb "
        "comp_frozen_flags inj_freq_Hz R1_hat_ohm comp_live_flag rotor_rise_K R1_id_status_code"
    ).split()
)


#: Exported columns renamed to follow the naming glossary (docs/architecture.md: ``_hat`` is
#: an estimate): old name -> new name. The old name keeps answering, with a
#: ``DeprecationWarning``, for one release (until 0.3) wherever a column is read by name
#: (:class:`Columns`: ``SimulationResult.signals``, ``res[name]``, ``res.window(...)``).
RENAMED_COLUMNS = {"R2_est_ohm": "R2_hat_ohm", "R1_est_ohm": "R1_hat_ohm"}

#: Keys of :func:`imdrive.run.metrics.compensation_metrics` renamed the same way.
RENAMED_METRICS = {
    "R2_est_initial_ohm": "R2_hat_initial_ohm",
    "R2_est_final_ohm": "R2_hat_final_ohm",
    "R2_est_final_error_pct": "R2_hat_final_error_pct",
}


def current_name(name: str, renamed: dict[str, str] = RENAMED_COLUMNS, stacklevel: int = 3):
    """The present name of a column (or metric) ``name``, warning when it is a renamed one.

    Parameters
    ----------
    name : str
        A column name, old or new.
    renamed : dict, optional
        Old name -> new name (:data:`RENAMED_COLUMNS` or :data:`RENAMED_METRICS`).
    stacklevel : int, optional
        Passed to :func:`warnings.warn`, so the warning points at the caller's line.

    Returns
    -------
    str
        ``renamed[name]`` for an old name (after a ``DeprecationWarning``), else ``name``.
    """
    new = renamed.get(name)
    if new is None:
        return name
    warnings.warn(
        f"{name!r} is renamed {new!r} (the estimate is '_hat'); the old name stops working in 0.3",
        DeprecationWarning,
        stacklevel=stacklevel,
    )
    return new


def with_current_names(mapping, stacklevel: int = 3) -> dict:
    """``mapping`` (column -> values) with renamed columns' old names replaced by the new ones.

    Parameters
    ----------
    mapping : Mapping
        Columns read from the user, possibly under an old name (:data:`RENAMED_COLUMNS`).
    stacklevel : int, optional
        Passed to :func:`warnings.warn` for each old name found.

    Returns
    -------
    dict
        The same values under the present names; a ``DeprecationWarning`` per old name.
    """
    if not any(isinstance(k, str) and k in RENAMED_COLUMNS for k in mapping):
        return mapping
    return {current_name(k, stacklevel=stacklevel + 1): v for k, v in mapping.items()}


class Columns(dict):
    """Named columns (a ``dict``) that also answer a renamed column's old name.

    Reading an old name (``cols["R2_est_ohm"]``, ``.get``, ``in``) gives the column under its
    new name (:data:`RENAMED_COLUMNS`) with a ``DeprecationWarning``; iteration, ``keys()``
    and every export carry the new names only.
    """

    __slots__ = ()
    _renamed: dict[str, str] = RENAMED_COLUMNS

    def _new_name(self, key):
        """The new name of an old ``key`` present here, else None."""
        new = self._renamed.get(key) if isinstance(key, str) else None
        return new if new is not None and dict.__contains__(self, new) else None

    def __missing__(self, key):
        if self._new_name(key) is None:
            raise KeyError(key)
        return dict.__getitem__(self, current_name(key, self._renamed, stacklevel=3))

    def __contains__(self, key) -> bool:
        if dict.__contains__(self, key):
            return True
        if self._new_name(key) is None:
            return False
        current_name(key, self._renamed, stacklevel=3)
        return True

    def get(self, key, default=None):
        """The column ``key`` (an old name warns), or ``default`` when there is none."""
        if dict.__contains__(self, key):
            return dict.__getitem__(self, key)
        if self._new_name(key) is None:
            return default
        return dict.__getitem__(self, current_name(key, self._renamed, stacklevel=3))


class Metrics(Columns):
    """A metrics table (``dict``) that answers the old names of :data:`RENAMED_METRICS`."""

    __slots__ = ()
    _renamed = RENAMED_METRICS


def columns_from_log(
    log: np.ndarray, vector: bool, extra_units: dict | None = None
) -> dict[str, np.ndarray]:
    """Named, unit-carrying columns from a kernel log (a record array of the drive's log dtype).

    Parameters
    ----------
    log : numpy.ndarray
        The log records, SI units.
    vector : bool
        Field-oriented drive (the controller's columns too) or open loop.
    extra_units : dict, optional
        ``{field: (unit, scale)}`` of the estimator's own log fields (its settings class's
        ``estimator_log_units``); a standard column whose field the log lacks (another
        estimator's) is left out.

    Returns
    -------
    Columns
        ``{column: values}`` (a ``dict`` that answers renamed columns' old names with a
        ``DeprecationWarning``), the standard columns in their order, with the estimator's own
        before ``e_d0_demod_Wb``.
    """
    out = {}
    fields = set(log.dtype.names)
    names = list(VECTOR_COLUMNS if vector else OPEN_LOOP_COLUMNS)
    if vector:
        for field, (unit, scale) in (extra_units or {}).items():
            name = f"{field}_{unit}"
            if name not in names:
                names.insert(names.index("e_d0_demod_Wb"), name)
            if field in fields:
                out[name] = log[field] * scale
    for name in names:
        if name in _DIRECT and name not in out:
            field, scale = _DIRECT[name]
            if field in fields:
                out[name] = log[field] * scale
    ia, ib = log["i_alpha"], log["i_beta"]
    out["i_a_A"] = ia.copy()
    out["i_b_A"] = -0.5 * ia + SQ3_2 * ib
    out["i_c_A"] = -0.5 * ia - SQ3_2 * ib
    return Columns((n, out[n]) for n in names if n in out)


#: unit suffixes of the exported columns, longest first so ``_rad_s`` wins over ``_s``
_SUFFIXES = ("rad_s", "ohm", "rpm", "Nm", "Wb", "rad", "A", "V", "C", "s")


def time_window(signals: dict, t0, t1=None) -> Columns:
    """The columns restricted to ``t0 <= time_s <= t1`` (``t1`` default: the last row), the
    bounds checked (:class:`~imdrive.errors.ConfigError` naming ``t0`` or ``t1``)."""
    from imdrive.errors import ConfigError, check_number

    t = signals["time_s"]
    t0 = check_number(t0, "t0")
    t1 = t[-1] if t1 is None else check_number(t1, "t1")
    if t1 < t0:
        raise ConfigError("t1", f"must be >= t0 (t0 = {t0:g} s, t1 = {t1:g} s)")
    sel = (t >= t0) & (t <= t1)
    return Columns((k, v[sel]) for k, v in signals.items())


def window_mean(signals: dict, name, t0, t1=None) -> float:
    """Mean of column ``name`` over ``t0 <= time_s <= t1``; a name no column has, or a window
    holding no sample, is a :class:`~imdrive.errors.ConfigError`, never a NaN."""
    from imdrive.errors import ConfigError

    if not isinstance(name, str):
        raise ConfigError("name", f"must be a column name (str), got {type(name).__name__}")
    column = current_name(name, stacklevel=4)
    if column not in signals:
        raise ConfigError("name", f"no column {name!r} in this run (res.columns lists them)")
    values = time_window(signals, t0, t1)[column]
    if values.size == 0:
        t = signals["time_s"]
        span = f"{t[0]:g}..{t[-1]:g} s" if len(t) else "no sample"
        raise ConfigError("t0", f"the window holds no sample (the run spans {span})")
    return float(np.mean(values))


def unit_of(column: str) -> str:
    """The unit a column's name ends with; ``"1"`` for a dimensionless column."""
    for u in _SUFFIXES:
        if column.endswith("_" + u):
            return "rad/s" if u == "rad_s" else u
    return "1"
