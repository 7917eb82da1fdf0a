"""Sensors: what the controller measures of the plant.

Today the current sensor adds a constant offset to the stator current space vector (the
``[sensor]`` section); gain errors, noise and quantisation plug in here.
"""

from numba import njit

from imdrive.kernels.records import c16, record_dtype

#: Parameters of the sensors.
SENSOR_PARAMS = record_dtype(
    [
        ("i_offset_ab", c16),  # offset added to the measured stator current, A
    ]
)


@njit(cache=True)
def measure_current(p, i_s_a, i_s_b):
    """Measured stator current ``(i_alpha, i_beta)``, A: the true one plus the offset."""
    return i_s_a + p.i_offset_ab.real, i_s_b + p.i_offset_ab.imag
