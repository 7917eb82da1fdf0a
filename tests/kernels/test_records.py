"""Record helpers of kernels/records.py."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from numba import njit

from imdrive.kernels.engine import LOG
from imdrive.kernels.records import copy_row


@njit
def _copy(dst, i, src, j):
    copy_row(dst, i, src, j)


def test_copy_row_copies_one_record_whole():
    rng = np.random.default_rng(1)
    src = np.frombuffer(rng.bytes(3 * LOG.itemsize), dtype=LOG).copy()
    dst = np.zeros(4, dtype=LOG)
    _copy(dst, 2, src, 1)
    assert dst[2].tobytes() == src[1].tobytes()
    assert dst[[0, 1, 3]].tobytes() == bytes(3 * LOG.itemsize)  # nothing else written
    _copy(dst, -1, src, 0)  # negative indices wrap, as numba's own indexing
    assert dst[3].tobytes() == src[0].tobytes()


def test_copy_row_refuses_two_dtypes():
    a = np.zeros(2, dtype=[("x", "f8")])
    b = np.zeros(2, dtype=[("y", "f8")])
    with pytest.raises(numba.core.errors.TypingError):
        _copy(a, 0, b, 0)
