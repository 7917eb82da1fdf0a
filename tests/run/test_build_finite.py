"""The finite check of a drive's records (:func:`imdrive.run.build.check_finite`): the joint
check over all records at once finds what the check record by record finds."""

from __future__ import annotations

import numpy as np
import pytest

from imdrive.config.scenario import Scenario
from imdrive.run import build


@pytest.fixture(scope="module")
def records():
    a = build.build_arrays(Scenario.read("sensorless-realistic", ["simulation.t_end_s=0.01"]))
    return [r.copy() for rs in (a.params, a.state0) for r in rs]


def test_a_drive_built_from_a_preset_is_finite(records):
    assert build._all_finite_joint(records)
    assert all(build._all_finite(r) for r in records)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_every_float_field_and_array_is_checked(records, bad):
    checked = 0
    for k, rec in enumerate(records):
        fields = rec.dtype.names or (None,)
        for f in fields:
            arr = rec if f is None else rec[f]
            if arr.dtype.kind not in "fc" or arr.size == 0:
                continue
            spoilt = [r.copy() for r in records]
            target = spoilt[k] if f is None else spoilt[k][f]
            flat = target.reshape(-1)
            flat[-1] = bad if arr.dtype.kind == "f" else complex(0.0, bad)
            assert not build._all_finite_joint(spoilt), (k, f)
            assert not build._all_finite(spoilt[k]), (k, f)
            checked += 1
    assert checked > 100  # the drive's float fields and profile arrays


def test_integers_and_flags_are_not_read_as_floats(records):
    # an int64 field whose bytes spell a NaN in float64 is not a non-finite number
    for k, rec in enumerate(records):
        ints = [f for f in rec.dtype.names or () if rec[f].dtype.kind in "iu"]
        if ints:
            spoilt = [r.copy() for r in records]
            spoilt[k][ints[0]] = np.array([np.nan]).view(np.int64)[0]
            assert build._all_finite_joint(spoilt)
            return
    pytest.fail("no integer field")
