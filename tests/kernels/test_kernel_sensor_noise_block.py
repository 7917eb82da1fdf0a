"""The current sensors' noise drawn a block of samples ahead (kernels/sensors.py).

The loop reads each sample's pair of normal numbers from a block drawn in a loop of its own
(:func:`noise_pair`); they must be :func:`gaussian_pair`'s numbers bit for bit, whatever order
the samples come in (a continued run starts anywhere, a batch block starts again at 0).
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from imdrive.kernels.records import new_record
from imdrive.kernels.sensors import (
    NOISE_BLOCK,
    SENSOR_PARAMS,
    gaussian_pair,
    measure_current,
    measure_current_drawn,
    noise_pair,
)
from imdrive.kernels.stages import SCRATCH


@njit(error_model="numpy")
def _drawn(p, ks, i_a, i_b):
    """measure_current_drawn and measure_current over the samples ``ks``, in the loop's
    setting: a local scratch record, numpy's error model."""
    scratch = np.zeros(1, dtype=SCRATCH)
    out = np.zeros((len(ks), 4))
    for j in range(len(ks)):
        a, b = measure_current_drawn(p, i_a[j], i_b[j], ks[j], scratch[0])
        c, d = measure_current(p, i_a[j], i_b[j], ks[j])
        out[j, 0], out[j, 1], out[j, 2], out[j, 3] = a, b, c, d
    return out


def test_block_gives_the_pairs_of_every_sample_in_any_order():
    buf = np.zeros(1, dtype=SCRATCH)[0]
    ks = [*range(0, 3 * NOISE_BLOCK + 5), 7, 6, 1000, 999, 1001, 2**40, 0, NOISE_BLOCK]
    for k in ks:
        assert noise_pair(11, k, buf) == gaussian_pair(11, k), k
    assert buf["noise_n"] == NOISE_BLOCK


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_drawn_measurement_is_the_measurement_bit_for_bit():
    p = new_record(
        SENSOR_PARAMS, phase_model=True, gain_a=1.0025, gain_b=0.9975, offset_a=0.02,
        offset_b=-0.02, noise_rms=0.02, adc_bits=12, adc_range=50.0, seed=3, vdc_gain=1.0,
    )[0]  # fmt: skip
    n = 5 * NOISE_BLOCK + 3
    rng = np.random.default_rng(0)
    ks = np.concatenate([np.arange(n), np.arange(500, 500 + n)]).astype(np.int64)
    i_a, i_b = rng.normal(0.0, 8.0, (2, len(ks)))
    out = _drawn(p, ks, i_a, i_b)
    assert np.array_equal(out[:, :2], out[:, 2:])
    quiet = new_record(SENSOR_PARAMS, phase_model=True, gain_a=1.0, gain_b=1.0, vdc_gain=1.0)[0]
    out = _drawn(quiet, ks, i_a, i_b)  # no noise: nothing drawn, the same numbers
    assert np.array_equal(out[:, :2], out[:, 2:])
