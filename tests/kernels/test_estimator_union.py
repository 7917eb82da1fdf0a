"""A batch of several estimators runs them in one compiled loop, on union records
(imdrive.kernels.estimators.union), and each drive gives the bits it gives alone."""

from __future__ import annotations

import numpy as np
import pytest
from numba.np.numpy_support import as_dtype

from imdrive.config.scenario import Scenario
from imdrive.kernels.batch import _worker
from imdrive.kernels.estimators import union
from imdrive.kernels.estimators.registry import kernel, kernel_names
from imdrive.run.batch import simulate_batch
from imdrive.run.batch_groups import united
from imdrive.run.build import build_arrays
from imdrive.run.simulate import simulate

ESTIMATORS = ("mras", "afo", "ekf", "smo-mras", "reactive-mras")


def _scenario(est: str, *extra: str) -> Scenario:
    # a ramp to 600 rpm: the AFO and the EKF orient on their own flux above 0.1 of the rated
    # stator frequency, so both of the drive's frames run
    return Scenario.read(
        "sensorless",
        [
            f'control.speed_feedback="{est}"',
            "simulation.t_end_s=0.6",
            "control.speed_ref_rpm={initial=0, changes=[{at=0.25, to=600, over=0.2}]}",
            "load.torque_Nm=4",
            *extra,
        ],
    )


def test_the_union_holds_every_registered_estimator_by_name_and_reads_back_from_its_records():
    params, state = union.union_of()
    ks = union.members(params)
    assert [k.name for k in ks] == sorted(kernel_names())
    assert union.members(state) == ks
    assert union.state_of(params) == state
    # the first field names the members: two unions are never taken for one another
    assert params.names[0] == state.names[0] and "ekf" in params.names[0]
    assert union.members(kernel("mras").params) is None
    log = union.logged(params).log_fields
    for k in ks:
        assert set(k.log_fields) <= set(log)
    with pytest.raises(ValueError, match="1 records of no estimator"):  # none left at zeros
        union.to_union(params, [np.zeros(1, np.dtype([("x", "f8")]))])


@pytest.mark.parametrize("est", ESTIMATORS)
def test_records_go_into_the_union_and_come_back_the_same_bytes(est):
    a = build_arrays(_scenario(est))
    params, state = union.union_of()
    mras = build_arrays(_scenario("mras"))
    for dt, own, other in (
        (params, a.params.est, mras.params.est),
        (state, a.state0.est, mras.state0.est),
    ):
        rows = union.to_union(dt, [other, own])
        j = int(rows[dt.names[0]][1])
        assert union.members(dt)[j].name == est
        back = union.from_union(rows[1:])
        assert back.dtype == own.dtype and back.tobytes() == own.tobytes()


def test_groups_that_differ_only_by_estimator_are_joined():
    mras, afo = (build_arrays(_scenario(e)) for e in ("mras", "afo"))
    comp = mras.params.comp.dtype
    other_comp = np.dtype([("x", "f8")])
    groups = {
        (1, mras.params.est.dtype, comp): ["m"],
        (1, afo.params.est.dtype, comp): ["a"],
        (10, afo.params.est.dtype, comp): ["a10"],  # another decimation: a call of its own
        (1, afo.params.est.dtype, other_comp): ["law"],  # another R2 law: its own records
    }
    out = united(groups)
    assert out == {
        (1, union.union_of()[0], comp): ["m", "a"],
        (10, afo.params.est.dtype, comp): ["a10"],
        (1, afo.params.est.dtype, other_comp): ["law"],
    }


@pytest.mark.slow  # end to end: five estimators' closed loops, one compiled union loop
def test_a_batch_of_five_estimators_is_one_loop_and_each_drive_its_single_run():
    scs = [_scenario(e) for e in ESTIMATORS]
    scs.append(_scenario("afo", "control.speed_ref_rpm=300"))  # a second drive of one member
    before = set(_worker.overloads)
    batch = simulate_batch(scs, logs=True)
    new = set(_worker.overloads) - before
    assert len(new) <= 1  # one loop (none: this process compiled it already)
    assert any(union.members(as_dtype(sig[0].types[5].dtype)) for sig in _worker.overloads)
    for sc, many in zip(scs, batch.results, strict=True):
        one = simulate(sc)
        assert many.status == one.status == 0
        assert list(many.signals) == list(one.signals)  # its own estimator's columns only
        for name, v in one.signals.items():
            assert np.array_equal(many.signals[name], v), (sc.control.speed_feedback, name)
        for f in one.state_final._fields:
            a, b = getattr(many.state_final, f), getattr(one.state_final, f)
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), f
