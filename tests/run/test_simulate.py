"""The kernel log a run or a batch hands the loop (imdrive.run.simulate.new_log)."""

from __future__ import annotations

import numpy as np

from imdrive.kernels.engine import LOG, log_dtype
from imdrive.kernels.estimators import union
from imdrive.run.simulate import new_log


def test_a_batch_log_of_every_estimator_is_nan_everywhere():
    # a union's log (every estimator's columns), as bench-estimators' batch makes it
    dtype = log_dtype(union.logged(union.union_of()[0]), None)
    log = new_log((3, 5), dtype)
    assert log.dtype == dtype and log.shape == (3, 5)
    for name in dtype.names:
        assert np.isnan(log[name]).all(), name
    assert new_log(4).dtype == LOG


def test_a_log_with_a_field_not_a_float_is_filled_as_numpy_fills_it():
    dtype = np.dtype([("time", "f8"), ("flag", "f4"), ("speed", "f8")])  # padding-free, mixed
    log = new_log(3, dtype)
    assert log.dtype == dtype
    assert np.isnan(log["time"]).all() and np.isnan(log["flag"]).all()
