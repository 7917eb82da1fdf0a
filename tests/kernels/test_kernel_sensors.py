"""The current-sensor kernel alone, on hand-made records (kernels/sensors.py).

The vector model adds its offset; the per-phase model measures phases a and b with their own
gain and offset, reconstructs beta from ``i_c = -i_a - i_b``, quantises like a mid-tread ADC and
adds Gaussian noise that is a function of (seed, sample, phase) only.
"""

import math

import numpy as np
import pytest

from imdrive.kernels.records import new_record
from imdrive.kernels.sensors import SENSOR_PARAMS, gaussian, measure_current, quantise


def _sensors(**kw):
    values = {"gain_a": 1.0, "gain_b": 1.0, "vdc_gain": 1.0, **kw}
    return new_record(SENSOR_PARAMS, **values)[0]


def _phases(i_alpha, i_beta):
    return i_alpha, -0.5 * i_alpha + 0.5 * math.sqrt(3.0) * i_beta


def test_vector_model_adds_the_offset_only():
    p = _sensors(i_offset_ab=0.3 - 0.2j)
    assert measure_current(p, 4.0, -1.0, 7) == (4.0 + 0.3, -1.0 - 0.2)


@pytest.mark.parametrize("i", [(10.0, 0.0), (-3.0, 7.0), (0.0, -12.5)])
def test_ideal_phase_sensors_give_back_the_vector(i):
    p = _sensors(phase_model=True)
    assert measure_current(p, *i, 0) == pytest.approx(i, abs=1e-12)


def test_phase_gains_and_offsets_enter_per_phase():
    g_a, g_b, o_a, o_b = 1.02, 0.97, 0.05, -0.08
    p = _sensors(phase_model=True, gain_a=g_a, gain_b=g_b, offset_a=o_a, offset_b=o_b)
    i = (8.0, -3.0)
    ia, ib = _phases(*i)
    ma, mb = g_a * ia + o_a, g_b * ib + o_b
    want = (ma, (ma + 2.0 * mb) / math.sqrt(3.0))  # i_c = -i_a - i_b
    assert measure_current(p, *i, 0) == pytest.approx(want, rel=1e-12)
    # a pure offset on phase a alone: an error vector along alpha and its beta projection
    p = _sensors(phase_model=True, offset_a=0.1)
    ea, eb = np.subtract(measure_current(p, 0.0, 0.0, 0), (0.0, 0.0))
    assert (ea, eb) == pytest.approx((0.1, 0.1 / math.sqrt(3.0)), rel=1e-12)


def test_quantise_is_a_mid_tread_adc():
    bits, fs = 10, 50.0
    q = 2 * fs / 2**bits
    assert quantise(0.3 * q, bits, fs) == 0.0  # mid-tread: zero is a level
    assert quantise(0.7 * q, bits, fs) == pytest.approx(q)
    assert quantise(-2.6 * q, bits, fs) == pytest.approx(-3 * q)
    assert quantise(1e3, bits, fs) == pytest.approx(fs - q)  # clipped at the range
    assert quantise(-1e3, bits, fs) == -fs
    assert quantise(1.234, 0, fs) == 1.234  # no ADC
    u = np.linspace(-40.0, 40.0, 2001)
    err = np.array([quantise(x, bits, fs) for x in u]) - u
    assert np.max(np.abs(err)) <= 0.5 * q + 1e-12


def test_quantised_measurement_lies_on_the_adc_grid():
    bits, fs = 12, 40.0
    q = 2 * fs / 2**bits
    p = _sensors(phase_model=True, adc_bits=bits, adc_range=fs)
    i = (7.3, -2.1)
    ma, mbeta = measure_current(p, *i, 0)
    assert ma / q == pytest.approx(round(ma / q), abs=1e-9)
    assert abs(ma - i[0]) <= 0.5 * q
    mb = (math.sqrt(3.0) * mbeta - ma) / 2.0  # phase b back from beta
    assert mb / q == pytest.approx(round(mb / q), abs=1e-9)


def test_noise_is_reproducible_by_seed_and_sample():
    p = _sensors(phase_model=True, noise_rms=0.2, seed=11)
    a = [measure_current(p, 5.0, 1.0, k) for k in range(50)]
    b = [measure_current(p, 5.0, 1.0, k) for k in reversed(range(50))][::-1]
    assert a == b  # a function of (seed, k): call order does not matter
    q = _sensors(phase_model=True, noise_rms=0.2, seed=12)
    assert measure_current(q, 5.0, 1.0, 3) != a[3]
    assert gaussian(11, 3, 0) != gaussian(11, 3, 1)  # phases draw independently


def test_noise_statistics():
    """Per phase: zero mean, the set rms, no correlation between phases or successive
    samples (bounds of about 4 standard errors for 20000 samples)."""
    n, rms = 20000, 0.15
    p = _sensors(phase_model=True, noise_rms=rms, seed=3)
    m = np.array([measure_current(p, 0.0, 0.0, k) for k in range(n)])
    na = m[:, 0]
    nb = (math.sqrt(3.0) * m[:, 1] - m[:, 0]) / 2.0
    for x in (na, nb):
        assert abs(x.mean()) < 4 * rms / math.sqrt(n)
        assert x.std() == pytest.approx(rms, rel=0.02)
        assert abs(np.corrcoef(x[:-1], x[1:])[0, 1]) < 4 / math.sqrt(n)
    assert abs(np.corrcoef(na, nb)[0, 1]) < 4 / math.sqrt(n)
    g = np.array([gaussian(1, k, 0) for k in range(n)])
    # the normal's fourth moment (3) and tail mass beyond 2 sigma (4.55 %)
    assert np.mean(g**4) == pytest.approx(3.0, abs=0.15)
    assert np.mean(np.abs(g) > 2.0) == pytest.approx(0.0455, abs=0.006)


def test_the_controllers_calibration_reads_both_phases_with_the_gains_geometric_mean():
    # controller_model.current_gain_b_per_a = k: the readings times sqrt(k) and 1/sqrt(k)
    g_a, g_b = 1.0025, 0.9975
    k = g_b / g_a
    p = _sensors(
        phase_model=True,
        gain_a=g_a,
        gain_b=g_b,
        cal_a=math.sqrt(k) - 1.0,
        cal_b=1.0 / math.sqrt(k) - 1.0,
    )
    g = math.sqrt(g_a * g_b)
    for i in [(8.0, -3.0), (-2.0, 11.0)]:
        assert measure_current(p, *i, 0) == pytest.approx((g * i[0], g * i[1]), rel=1e-12)
    uncal = measure_current(_sensors(phase_model=True, gain_a=g_a, gain_b=g_b), 0.0, 10.0, 0)
    assert abs(uncal[1] / 10.0 - g) > 1e-3  # uncalibrated: beta reads with neither gain
