"""The optional blocks a drive compiles (kernels/features.py).

That every preset still gives its stored results bit for bit with only its own blocks compiled
is tests/drive/test_preset_baseline.py's; here: which blocks a drive's records select, that a
block outside them is never typed, and that a batch compiles what any of its drives runs.
"""

import warnings

import numpy as np
import pytest
from numba import njit
from numba.core.errors import TypingError

from imdrive.config.scenario import Scenario
from imdrive.kernels import features
from imdrive.run.batch import stack_drives
from imdrive.run.build import build_arrays


def _names(preset, *sets):
    return build_arrays(Scenario.read(preset, list(sets))).params.features.dtype.names[1:]


TRACKING = {"r2_tracking", "standstill_r1"}
REALISTIC = {"switching_bridge", "inverter_compensation", "phase_sensors"}


def test_each_drive_compiles_the_groups_of_blocks_its_records_run():
    assert _names("sensorless") == ()
    assert set(_names("injection-robust")) == TRACKING
    assert set(_names("paper-fig5")) == TRACKING  # no standstill test: its group's all the same
    assert set(_names("sensorless-realistic")) == REALISTIC
    assert set(_names("injection-fig5-realistic")) == TRACKING | REALISTIC
    # a setting that turns a block on turns its group on
    assert set(_names("sensorless", 'inverter.model="switching"')) == REALISTIC


def test_the_groups_partition_the_features():
    grouped = [name for group in features.GROUPS for name in group]
    assert sorted(grouped) == sorted(features.FEATURES)


def test_a_batch_compiles_what_any_of_its_drives_runs():
    # one estimator (a batch groups its drives by estimator): the recommended drive on the MRAS
    drives = (("sensorless", ()), ("injection-robust", ('control.speed_feedback="mras"',)))
    arrays = [build_arrays(Scenario.read(n, list(o))) for n, o in drives]
    params, _ = stack_drives(arrays)
    assert params.features.shape == (2,)
    assert set(params.features.dtype.names[1:]) == TRACKING
    assert features.has(params.features, "r2_tracking")
    assert not features.has(params.features, "switching_bridge")
    assert features.has(None, "switching_bridge")  # no features array: every block


@njit
def _untypable(x):
    return x.no_such_attribute  # typing this fails: it must never be typed when off


@njit
def _stand_in(x):
    return -1.0


_gated = features.compiled("switching_bridge", _stand_in)(_untypable)


@njit
def _call(feat, x):
    return _gated(feat, x)


def test_a_block_outside_the_drive_s_features_is_never_typed():
    off = np.ones(1, dtype=features.features_dtype(["r2_tracking"]))
    assert _call(off[0], 2.0) == -1.0
    with pytest.raises(TypingError, match="no_such_attribute"):
        _call(np.ones(1, dtype=features.EVERY)[0], 2.0)
    with pytest.raises(TypingError, match="no_such_attribute"):
        _call(None, 2.0)  # None: every block compiled


def test_the_wrapper_called_from_python_runs_the_block():
    twice = features.compiled("phase_sensors", _stand_in)(njit(lambda x: 2.0 * x))
    assert twice(None, 2.0) == 4.0


def test_unknown_features_are_refused_by_name():
    with pytest.raises(KeyError, match="warp_drive"):
        features.features_dtype(["warp_drive"])
    with pytest.raises(KeyError, match="warp_drive"):
        features.compiled("warp_drive", _stand_in)


@pytest.mark.slow
def test_a_drive_without_a_features_array_compiles_every_block_and_runs_the_same():
    # DriveParams built by hand before the field existed: features None, every block compiled
    # (the engine of before); the realistic drive's blocks all run, bit for bit
    from dataclasses import replace

    from imdrive.run.simulate import simulate

    sc = Scenario.read("injection-fig5-realistic", ["simulation.t_end_s=0.05"])
    a = build_arrays(sc)
    every = replace(a, params=a.params._replace(features=None))
    got, want = simulate(sc, arrays=every), simulate(sc, arrays=a)
    assert got.status == want.status
    assert list(got.signals) == list(want.signals)
    for col in want.signals:
        assert np.array_equal(got.signals[col], want.signals[col], equal_nan=True), col


_twice_gated = features.compiled("switching_bridge", _stand_in)(njit(lambda x: 2.0 * x))


@njit
def _own_dispatcher(feat, x):  # not inlined, as foc_step: a specialisation per features type
    return _twice_gated(feat, x)


@njit
def _caller(feat, x):
    return _own_dispatcher(feat, x)


def test_a_function_compiled_for_fewer_blocks_is_never_reused_for_more():
    # numba may pass a record where a record of a prefix of its fields is expected (width
    # subtyping): the lean drive's foc_step then ran for a drive with the inverter
    # compensation, whose online scale never adapted (the clean-clone CI of 2026-11-30)
    lean = np.ones(1, dtype=features.features_dtype(()))[0]
    bridge = np.ones(1, dtype=features.features_dtype(["switching_bridge"]))[0]
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        assert _caller(lean, 2.0) == -1.0
        assert _caller(bridge, 2.0) == 4.0
    # not even considered: which specialisation wins may depend on what a process compiled
    assert not [w for w in seen if "subtype" in str(w.message)]
