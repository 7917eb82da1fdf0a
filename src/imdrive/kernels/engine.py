"""The simulation loop: a discrete controller at period Ts driving the continuous plant.

Each control period ``[t_k, t_k + Ts)``:

1. sample the plant (current through the sensors, speed) at ``t_k``;
2. run the estimator (MRAS) and the R2 compensator (which acts at its own period);
3. run the controller (open-loop voltage or field-oriented control) -> voltage reference;
4. the inverter turns it into voltage segments, held over the period (zero-order hold);
5. integrate the plant over the period, segment by segment
   (:func:`imdrive.kernels.machine.integrate_segment`).

A drive is two named tuples of record arrays (one record dtype per block, see
:mod:`imdrive.kernels.records`): :class:`DriveParams` (constant over a run) and
:class:`DriveState` (updated in place). Each array has one row per drive, so the same compiled
:func:`run_drive` serves one drive (``N = 1``, ``i = 0``) and the batch (:mod:`.batch`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from imdrive.kernels import compensator, ifoc, inverter, machine, model, sensors
from imdrive.kernels.bridge import switching_period  # noqa: F401  (re-exported: old path)
from imdrive.kernels.estimators import afo, ekf, mras, reactive_mras, registry, smo_mras, union  # noqa: F401  (the package's estimators register on import; a batch's union of them)
from imdrive.kernels.features import row as features_row
from imdrive.kernels.features import switching_bridge
from imdrive.kernels.inverter import INV_SWITCHING, MAX_EVENTS  # noqa: F401  (MAX_EVENTS: old path)
from imdrive.kernels.jit import njit
from imdrive.kernels.recording import record_after, record_before
from imdrive.kernels.records import b1, c16, f8, i8, record_dtype
from imdrive.kernels.stages import (
    NO_ESTIMATE,
    S_CURRENT,
    S_NAN,
    S_OK,
    S_SPEED,
    SCRATCH,
    check,
    control,
    estimate,
    log_row,
    measure,
    modulate,
    plant,
    profiles,
)

DRIVE_OPEN_LOOP = 0
DRIVE_FOC = 1

#: ``control.speed_feedback`` -> the registered estimator that runs ("measured" runs the MRAS
#: beside the measured speed feedback, its estimate logged)
MEASURED_RUNS = "mras"

__all__ = ["S_OK", "S_NAN", "S_CURRENT", "S_SPEED", "MAX_EVENTS", "log_dtype"]

#: Parameters of the loop itself.
SIM_PARAMS = record_dtype(
    [
        ("Ts", f8),  # control period, s
        ("nsub", i8),  # RK4 sub-steps per segment
        ("i_lim", f8),  # divergence bound on |i_s|, A
        ("w_lim", f8),  # divergence bound on |w_m|, rad/s
        ("mode", i8),  # DRIVE_OPEN_LOOP or DRIVE_FOC
        ("sensorless", b1),  # speed feedback: the MRAS estimate instead of the measured speed
        ("delay", i8),  # computation delay, periods: 0, or 1 (the reference of sample k acts
        # over the next period, as on a DSP)
        ("flux_inj_amp", f8),  # flux-command injection: relative amplitude (0: off)
        ("flux_inj_freq", f8),  # its frequency, Hz
    ]
)

#: What the controller keeps from one sample to the next.
SAMPLE_STATE = record_dtype(
    [
        ("v_prev_ab", c16),  # voltage the controller commanded for the last period, V
        ("i_prev_ab", c16),  # current measured at the last sample, A
        ("v_hold_ab", c16),  # with a one-period delay: the reference waiting for the next period
        ("dv_hold_ab", c16),  # and the dead-time compensation it contains, V
        ("v_use", f8),  # the last commanded voltage, compensation included, over Vdc/sqrt 3
    ]
)

#: The log fields every drive has: the sample time, then every block's declared fields (SI
#: units); the estimator's ``speed_est``, ``e_d0`` and ``e_q0`` come from the values its step
#: returns. A drive's log adds its estimator's own fields (:func:`log_dtype`).
BASE_LOG_FIELDS = (
    ("time",)
    + machine.LOG_FIELDS
    + inverter.LOG_FIELDS
    + sensors.LOG_FIELDS
    + ifoc.LOG_FIELDS
    + ("speed_est", "e_d0", "e_q0")
    + model.LOG_FIELDS
    + compensator.LOG_FIELDS
)


def log_dtype(estimator: str | registry.EstimatorKernel = "mras", law=None) -> np.dtype:
    """The log record of a drive with ``estimator``: the base fields, then the estimator's own
    (in the order of the MRAS log of 0.2 for the MRAS, so its columns keep their place: a base
    field the estimator also declares, ``R1_id_status``, is placed among its own), then those
    of the plug-in R2 ``law`` (a :class:`~imdrive.kernels.r2_law_registry.LawKernel`), if any."""
    k = registry.kernel(estimator) if isinstance(estimator, str) else estimator
    base = list(BASE_LOG_FIELDS)
    at = base.index("e_q0") + 1
    own = list(k.log_fields)
    names = [f for f in base[:at] if f not in own] + own + [f for f in base[at:] if f not in own]
    names += [f for f in (law.log_fields if law is not None else ()) if f not in names]
    return record_dtype([(name, f8) for name in names])


#: The log record of an MRAS drive (every preset's), kept under its 0.2 name.
LOG = log_dtype("mras")
LOG_FIELDS = LOG.names


class DriveParams(NamedTuple):
    """A drive's constant inputs; every field has one row per drive (first axis)."""

    sim: np.ndarray  # SIM_PARAMS
    plant: np.ndarray  # machine.PLANT_PARAMS
    inverter: np.ndarray  # inverter.INVERTER_PARAMS
    sensor: np.ndarray  # sensors.SENSOR_PARAMS
    control: np.ndarray  # ifoc.CONTROL_PARAMS
    est: np.ndarray  # the estimator's params record (its EstimatorKernel.params)
    comp: np.ndarray  # compensator.COMPENSATOR_PARAMS
    prof_t: np.ndarray  # float64[N, N_PROF, K] profile breakpoint times, s
    prof_v: np.ndarray  # float64[N, N_PROF, K] profile values (SI)
    prof_n: np.ndarray  # int64[N, N_PROF] breakpoints per profile
    tables: np.ndarray  # float64[T, 13, 13] fuzzy lookup tables
    table_idx: np.ndarray  # int64[N] each drive's table
    #: the optional blocks compiled in, named by the dtype (kernels/features.py ``of``);
    #: ``None``: every one
    features: np.ndarray | None = None


class DriveState(NamedTuple):
    """A drive's state, updated in place; every field has one row per drive."""

    plant: np.ndarray  # machine.PLANT_STATE
    sample: np.ndarray  # SAMPLE_STATE
    model: np.ndarray  # model.MODEL_STATE
    control: np.ndarray  # ifoc.CONTROL_STATE
    est: np.ndarray  # the estimator's state record (its EstimatorKernel.state, tagged)
    comp: np.ndarray  # compensator.COMPENSATOR_STATE
    inverter: np.ndarray  # inverter.INVERTER_STATE


_OLD_ESTIMATOR_FIELDS = {"mras": "mras", "rmras": "reactive-mras", "afo": "afo", "ekf": "ekf"}


def _old_estimator_field(self, name):
    """The 0.2 per-estimator fields (``P.mras``, ``S.ekf``, ...), deprecated for ``.est``."""
    est = _OLD_ESTIMATOR_FIELDS.get(name)
    if est is None:
        raise AttributeError(name)
    import warnings

    warnings.warn(
        f"DriveParams/DriveState.{name} is deprecated: a drive carries only its own "
        "estimator's records, in .est",
        DeprecationWarning,
        stacklevel=2,
    )
    if registry.kernel_of_state(self.est.dtype).name != est:
        raise AttributeError(f"this drive's estimator is not {est!r}: its records are in .est")
    return self.est


DriveParams.__getattr__ = _old_estimator_field
DriveState.__getattr__ = _old_estimator_field


@njit(cache=True, entry=True, error_model="numpy")
def run_drive(P, S, i, n_steps, log, log_every, k0=0, final=True, rec=None):
    """Simulate drive ``i`` of ``P``/``S`` for ``n_steps`` control periods (``S`` in place).

    Compiled with numpy's error model: a division by zero in the loop gives inf or NaN, which
    the divergence check reports (``S_NAN``), instead of raising; the exception branches would
    keep numba from pruning the reference counts of the stages' arguments (atomic, every
    period).

    Parameters
    ----------
    P : DriveParams
    S : DriveState
        State at the start; final state on return.
    i : int
        The drive's row in every array of ``P`` and ``S``.
    n_steps : int
        Number of control periods.
    log : LOG[n_rows]
        Receives one row every ``log_every`` periods, row r at t = r*log_every*Ts, including
        t = 0 and (when ``n_steps`` is a multiple of ``log_every``) t = n_steps*Ts.
        Pass an array with zero rows for no logging.
    log_every : int
    k0 : int
        Index of the first period: the run continues one that stopped after ``k0`` periods
        (time ``(k0 + k) Ts``), so consecutive calls reproduce one long call exactly.
    final : bool
        Whether to take (and log) the closing sample at ``k = n_steps``. A call that another
        will continue passes False: it returns right after integrating its last period.

    Returns
    -------
    status : int
        ``S_OK`` or the divergence code ``S_NAN``, ``S_CURRENT``, ``S_SPEED``.
    k_end : int
        Number of periods completed in this call (the period where divergence was found).
    """
    sim = P.sim[i]
    pp = P.plant[i]
    pinv = P.inverter[i]
    psen = P.sensor[i]
    pc = P.control[i]
    pe = P.est[i]
    pk = P.comp[i]
    pt = P.prof_t[i]
    pv = P.prof_v[i]
    pn = P.prof_n[i]
    table = P.tables[P.table_idx[i]]
    x = S.plant[i]
    sinv = S.inverter[i]
    smp = S.sample[i]
    mdl = S.model[i]
    ctl = S.control[i]
    est = S.est[i]
    cmp = S.comp[i]
    feat = features_row(P.features, i)  # the blocks compiled in (a type: kernels/features.py)

    Ts = sim.Ts
    nsub = max(sim.nsub, 1)
    foc = sim.mode == DRIVE_FOC
    switching = switching_bridge(pinv)
    Vdc_meas = psen.vdc_gain * pinv.Vdc
    n_rows = log.shape[0]

    # the loop's scratch; the array stays in use in the loop (a record of a local array does
    # not keep it alive, see kernels/records.py)
    scratch = np.zeros(1, dtype=SCRATCH)
    i_next_ab = 0j  # the plant's current after the last period (check), the next sample's
    have_next = False

    for k in range(n_steps + 1 if final else n_steps):
        t = (k0 + k) * Ts
        prof = profiles(pp, pt, pv, pn, t, foc, mdl, Ts)
        smpl = measure(feat, pp, psen, x, ctl, prof, t, k0 + k, i_next_ab, have_next, scratch[0])
        if rec is not None:  # pruned at compile time without a recording
            if k < rec.shape[0]:
                record_before(rec[k], smpl, mdl, ctl, smp)
        estm = NO_ESTIMATE
        if foc:
            estm = estimate(
                feat, sim, pp, pe, pk, table, x, mdl, ctl, est, cmp, smp, prof, smpl, Vdc_meas, pc,
            )  # fmt: skip
        cmd = control(feat, sim, pc, x, mdl, ctl, smp, prof, smpl, estm, foc)
        mod = modulate(pinv, pc, smp, smpl, cmd, switching, Vdc_meas, scratch[0], Ts)
        if rec is not None:
            if k < rec.shape[0]:
                w_fb = estm.w_r_hat / pp.n_p if sim.sensorless else x.w_m
                record_after(rec[k], x, smp, mdl, prof, estm, foc, w_fb)

        logged = log_every > 0 and k % log_every == 0 and k // log_every < n_rows
        if logged:
            row = log[k // log_every]
            log_row(row, pp, pe, x, mdl, ctl, est, cmp, prof, smpl, estm, cmd, mod.v_app_ab)
        if k == n_steps:
            break

        v_app_ab = plant(
            feat, pinv, sinv, pp, x, prof, mod, switching, Vdc_meas, nsub, scratch[0], Ts,
        )  # fmt: skip
        if switching and logged:  # the true average, known only now
            log[k // log_every].v_alpha = v_app_ab.real
            log[k // log_every].v_beta = v_app_ab.imag

        status, i_next_ab = check(sim, pp, x, smp, mdl, ctl, est, cmp, estm, scratch[0])
        have_next = True
        if status != S_OK:
            return status, k + 1
    return S_OK, n_steps
