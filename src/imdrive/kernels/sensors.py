"""Sensors: what the controller measures of the plant.

Current sensors
    The vector model (``phase_model`` off, the default) adds a constant offset to the stator current
    space vector. The per-phase model measures phases a and b (two sensors, ``i_c = -i_a - i_b``
    as in most drives), each with its own gain and offset, Gaussian noise (seeded, reproducible:
    a counter-based generator keyed by seed and drive sample, so a run, a continued run and a
    batch run draw the same numbers; the two phases take the two independent normals of one
    Box-Muller pair) and ADC quantisation (``bits`` over ``±range``,
    mid-tread, clipped at the range)::

        i_x,meas = Q(g_x i_x + o_x + n_x),   Q(u) = clip(q round(u/q), -range, range - q),
        q = 2 range / 2^bits

    and the controller scales the readings by its calibration ``1 + cal_x``
    (``sqrt(g_b/g_a)`` and ``sqrt(g_a/g_b)`` as commissioning measured the ratio: both phases
    then read with the gains' geometric mean, the common gain they had on average).

DC-link voltage sensor
    The controller turns voltages into duty cycles with ``Vdc_meas = g_dc Vdc``; a gain error
    scales every applied voltage by ``1/g_dc``.
"""

import math

import numpy as np

from imdrive.kernels.jit import njit
from imdrive.kernels.records import b1, c16, f8, i8, record_dtype

#: Parameters of the sensors.
SENSOR_PARAMS = record_dtype(
    [
        ("i_offset_ab", c16),  # offset added to the measured stator current vector, A
        ("phase_model", b1),  # per-phase current sensors below are active
        ("gain_a", f8),  # gain of the phase-a current sensor
        ("gain_b", f8),
        ("offset_a", f8),  # offset of the phase-a current sensor, A
        ("offset_b", f8),
        ("noise_rms", f8),  # rms of the Gaussian noise of each current sensor, A
        ("adc_bits", i8),  # ADC resolution, bits (0: no quantisation)
        ("adc_range", f8),  # ADC full scale, ±A
        ("seed", i8),  # noise seed
        ("vdc_gain", f8),  # gain of the DC-link voltage sensor
        # the controller's calibration of the two readings, which it multiplies by 1 + cal_a
        # and 1 + cal_b (sqrt(g_b/g_a) - 1 and sqrt(g_a/g_b) - 1 as commissioning measured
        # the ratio: both then read with the gains' geometric mean; 0: none)
        ("cal_a", f8),
        ("cal_b", f8),
    ]
)

#: Log fields written by the engine: the measured current, A.
LOG_FIELDS = ("i_alpha_meas", "i_beta_meas")

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)


@njit(cache=True, inline="always")
def _mix(z):
    """splitmix64's finaliser: a 64-bit hash with good avalanche (Steele, Lea, Flood 2014)."""
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


@njit(cache=True, inline="always")
def _uniform(seed, k, channel):
    """A uniform number in (0, 1) for (seed, sample, channel), independent of call order."""
    z = _mix(np.uint64(seed) * _GOLDEN + np.uint64(k))
    z = _mix(z + np.uint64(channel + 1) * _GOLDEN)
    return ((z >> np.uint64(11)) + np.uint64(1)) * (1.0 / 9007199254740994.0)


@njit(cache=True, inline="always")
def gaussian(seed, k, channel):
    """A standard normal number for (seed, sample, channel) (Box-Muller on two uniforms)."""
    u1 = _uniform(seed, k, 2 * channel)
    u2 = _uniform(seed, k, 2 * channel + 1)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@njit(cache=True, inline="always")
def gaussian_pair(seed, k):
    """Two independent standard normal numbers for (seed, sample): Box and Muller's pair
    ``r cos(2 pi u2), r sin(2 pi u2)``, ``r = sqrt(-2 ln u1)`` (Ann. Math. Statist. 29, 1958),
    of the uniforms of :func:`gaussian`'s channel 0, whose value is the first of the pair.
    One logarithm, one square root and one sine-cosine pair for both phases."""
    u1 = _uniform(seed, k, 0)
    u2 = _uniform(seed, k, 1)
    r = math.sqrt(-2.0 * math.log(u1))
    a = 2.0 * math.pi * u2
    return r * math.cos(a), r * math.sin(a)


@njit(cache=True)
def quantise(u, bits, full_scale):
    """Mid-tread ADC: ``bits`` over ``±full_scale`` (``bits = 0``: no quantisation)."""
    if bits <= 0:
        return u
    q = 2.0 * full_scale / (2.0**bits)
    v = q * round(u / q)
    return min(max(v, -full_scale), full_scale - q)


#: Samples of the current sensors' noise drawn at a time by the loop (:func:`noise_pair`).
NOISE_BLOCK = 16

#: The noise the loop draws ahead, fields of its scratch record
#: (:data:`imdrive.kernels.stages.SCRATCH`): one run_drive call's, not a drive's state.
NOISE_FIELDS = [
    ("noise_k0", i8),  # the sample of the block's first pair
    ("noise_n", i8),  # pairs in the block (0: none drawn yet)
    ("noise_a", f8, (NOISE_BLOCK,)),  # the pairs (gaussian_pair) of samples noise_k0, ...
    ("noise_b", f8, (NOISE_BLOCK,)),
]


@njit(cache=True)  # a call: inlined in numba's IR into run_drive, its loop drew other numbers
def noise_pair(seed, k, buf):
    """:func:`gaussian_pair` of sample ``k``, from the block of :data:`NOISE_BLOCK` pairs kept
    in ``buf`` (a record with :data:`NOISE_FIELDS`); a ``k`` outside it draws the block from
    ``k`` on. The same numbers as :func:`gaussian_pair` (a function of the seed and the sample
    alone), drawn in a loop of their own: the logarithms and sine-cosines, which do not depend
    on the drive, then run back to back instead of in the middle of the period's chain."""
    j = k - buf.noise_k0
    if j < 0 or j >= buf.noise_n:
        for i in range(NOISE_BLOCK):
            n_a, n_b = gaussian_pair(seed, k + i)
            buf.noise_a[i] = n_a
            buf.noise_b[i] = n_b
        buf.noise_k0 = k
        buf.noise_n = NOISE_BLOCK
        j = 0
    return buf.noise_a[j], buf.noise_b[j]


@njit(cache=True, inline="always")
def phase_sensors(p, i_s_alpha, i_s_beta, n_a, n_b):
    """The per-phase model's measured current ``(i_alpha, i_beta)`` (A), with the standard
    normal numbers ``n_a``, ``n_b`` of the sample (used only if ``p.noise_rms > 0``)."""
    ia = i_s_alpha
    ib = -0.5 * i_s_alpha + 0.5 * math.sqrt(3.0) * i_s_beta
    ma = p.gain_a * ia + p.offset_a
    mb = p.gain_b * ib + p.offset_b
    if p.noise_rms > 0.0:
        ma += p.noise_rms * n_a
        mb += p.noise_rms * n_b
    # the controller's scaling of counts to amperes: its calibration
    ma = quantise(ma, p.adc_bits, p.adc_range) * (1.0 + p.cal_a)
    mb = quantise(mb, p.adc_bits, p.adc_range) * (1.0 + p.cal_b)
    # two sensors, i_c = -i_a - i_b: alpha = i_a, beta = (i_a + 2 i_b)/sqrt(3)
    return ma + p.i_offset_ab.real, (ma + 2.0 * mb) / math.sqrt(3.0) + p.i_offset_ab.imag


@njit(cache=True)
def measure_current(p, i_s_alpha, i_s_beta, k):
    """Measured stator current ``(i_alpha, i_beta)`` at sample ``k``, A."""
    if not p.phase_model:
        return i_s_alpha + p.i_offset_ab.real, i_s_beta + p.i_offset_ab.imag
    n_a = 0.0
    n_b = 0.0
    if p.noise_rms > 0.0:
        n_a, n_b = gaussian_pair(p.seed, k)
    return phase_sensors(p, i_s_alpha, i_s_beta, n_a, n_b)


@njit(cache=True, inline="always")
def measure_current_drawn(p, i_s_alpha, i_s_beta, k, buf):
    """:func:`measure_current` with the noise from the block in ``buf`` (:func:`noise_pair`):
    the same numbers; the loop's."""
    if not p.phase_model:
        return i_s_alpha + p.i_offset_ab.real, i_s_beta + p.i_offset_ab.imag
    n_a = 0.0
    n_b = 0.0
    if p.noise_rms > 0.0:
        n_a, n_b = noise_pair(p.seed, k, buf)
    return phase_sensors(p, i_s_alpha, i_s_beta, n_a, n_b)
