"""The drive loop's late blocks, for a second process to compile while the first compiles the
loop (:mod:`imdrive.run.prefetch`).

numba compiles a separately compiled block when it types the call to it in the loop, and
first looks for it in the cache: a block another process has compiled and saved by then is
loaded in a few milliseconds instead of compiled. :func:`late_blocks` calls the blocks the
loop's stages call last (the plant's integration or the switching bridge, the log row, the
modulator, the inverter-error compensation and the field-oriented control; the optional ones
where the drive compiles them, :mod:`imdrive.kernels.features`) with the argument types the
stages give them, in the reverse of the loop's order, so that the second process compiles
first what the first one needs last. Compiling it (``late_blocks.compile``) types those
calls and so compiles and caches each block; it is never run. Measured on a cold cache
(2026-12-01, idle machine): the blocks of ``imdrive run sensorless`` it compiles took 4.0 s
of its 12.0 s cold start, compiled alone.
"""

from __future__ import annotations

import numpy as np

from imdrive.kernels.compensator import log_compensator
from imdrive.kernels.estimators.registry import EstimatorInput, estimator_log
from imdrive.kernels.features import row as features_row
from imdrive.kernels.ifoc import foc_step, log_control
from imdrive.kernels.inverter import inverter_segments
from imdrive.kernels.jit import njit
from imdrive.kernels.machine import integrate_segment, log_plant
from imdrive.kernels.r2_law_registry import law_log
from imdrive.kernels.r2_tracking import TrackingInput
from imdrive.kernels.stages import (
    SCRATCH,
    Sample,
    bridge,
    compensate_inverter,
    inverter_residual,
    run_r1_standstill,
    track_r2,
)


@njit  # not cached: only what it calls is kept
def late_blocks(P, S, log):
    """Call the loop's late blocks as :func:`imdrive.kernels.engine.run_drive`'s stages do
    (their arguments' types, not their values: compiled, never run)."""
    i = 0
    feat = features_row(P.features, i)  # the optional blocks: those this drive compiles
    sim = P.sim[i]
    pp = P.plant[i]
    pinv = P.inverter[i]
    pc = P.control[i]
    pe = P.est[i]
    x = S.plant[i]
    sinv = S.inverter[i]
    smp = S.sample[i]
    mdl = S.model[i]
    ctl = S.control[i]
    est = S.est[i]
    cmp = S.comp[i]
    Ts = sim.Ts
    nsub = max(sim.nsub, 1)
    scratch = np.zeros(1, dtype=SCRATCH)
    scr = scratch[0]
    z = 0.0
    Vdc_meas = P.sensor[i].vdc_gain * pinv.Vdc
    table = P.tables[P.table_idx[i]]
    inp = EstimatorInput(0j, 0j, 0j, z, z, 0j, z, z, False, Ts, z, ctl.dc_restart)
    ti = TrackingInput(z, z, 0, z, z, z, z, z, z, z, z, z, Ts)
    track_r2(feat, P.comp[i], cmp, mdl, table, 0j, inp, z, ti)
    # stages.plant
    bridge(feat, pinv, sinv, pp, x, z, z, Vdc_meas, z, z, z, Ts, nsub, scr.ev, scr.no_trace, scr, z)
    integrate_segment(pp, x, z, z, z, z, z, Ts, nsub, None)
    row = log[0]  # stages.log_row
    log_plant(row, pp, x, z, z, z, z, z)
    log_control(row, ctl, z, z)
    estimator_log(row, pe, est, pp.n_p)
    log_compensator(row, cmp)
    law_log(row, cmp.law)
    inverter_segments(pinv, z, z, z, z, Ts, scr.seg_dt, scr.seg_va, scr.seg_vb)  # modulate
    # stages.estimate's standstill R1 test, which the loop meets after the estimator: late
    # where a batch of several estimators types them all first (kernels/estimators/union.py)
    run_r1_standstill(feat, pc, mdl, ctl, z, z, z, z, z, z, z, ctl.w_e, Ts)
    smpl = Sample(z, 0, 0j, 0j, z)  # stages.control
    compensate_inverter(feat, pc, ctl, mdl, smp, smpl, Ts, z, z, z)
    inverter_residual(feat, pc, ctl, mdl, smp.v_prev_ab, smp.i_prev_ab, smpl.i_meas_ab, Ts)
    foc_step(pc, mdl, ctl, z, z, z, z, z, z, Ts, 0j, z)
