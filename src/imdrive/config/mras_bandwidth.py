"""The MRAS's adaptation bandwidth by default, from the speed loop's
(:func:`mras_bandwidth_Hz`), whether it runs the type-2 adaptation (:func:`mras_type2`,
which needs it), whether it normalises its error (:func:`mras_normalise`) and the online
R1 law's frequency bound (:func:`r1_max_freq_Hz`). Its own module:
:mod:`imdrive.config.perunit` imports :mod:`imdrive.config.mras_type`, and this needs the
speed loop's bandwidth from perunit.
"""

from __future__ import annotations

from imdrive.config.mras_type import (
    MRAS_RAMP_LAG_MAX_PU,
    mras_ramp_lag_pu,
    mras_type2_for_field_weakening,
)
from imdrive.config.perunit import speed_bandwidth_Hz

#: The MRAS's bandwidth when the speed loop does not ask for more, Hz
MRAS_BANDWIDTH_HZ = 20.0
#: ... and at least this multiple of the speed loop's bandwidth (:func:`mras_bandwidth_Hz`):
#: Table IV's drive, 20 Hz over a 5 Hz speed loop
MRAS_PER_SPEED_BANDWIDTH = 4.0


def mras_bandwidth_Hz(sc, mras=None) -> float:
    """The MRAS's adaptation bandwidth, Hz: ``mras.bandwidth_Hz`` if set, else
    :data:`MRAS_BANDWIDTH_HZ` (20 Hz) raised to :data:`MRAS_PER_SPEED_BANDWIDTH` (4) times the
    speed loop's bandwidth (:func:`imdrive.config.perunit.speed_bandwidth_Hz`), the ratio of
    Table IV's drive.

    The speed loop acts on the estimate, so the estimator's lag is inside it, and a cascade
    keeps its outer loop's margin when the inner (here the estimator) is several times
    faster. Where the speed loop is raised for a small inertia the estimator must follow. On
    the 2.2 kW Aalto machine (J = 0.015 kg m², its rated torque decelerating it at
    9300 rpm/s; speed loop 12.3 Hz) the ``sensorless`` drive at 5 % speed lost control at a
    rated motoring step whatever R2_hat: the rotor fell from 72 to -81 rpm within 30 ms while
    the 20 Hz estimate was still at 5 rpm, 85 rpm behind (beyond the MRAS's linear range
    ``1/T2`` = 45 rpm). With 49 Hz it holds. A faster speed loop instead (20 Hz, the rated
    step's dip halved) held the step too, but with the MRAS at 20 Hz the regenerating runs
    from 1.3 R2 swung 130-170 rpm, and with the MRAS at 60 Hz the switching bridge at 10 %
    speed and no load limit-cycled (14 rpm peak to peak; 0.9 rpm with this rule). Every
    other library machine keeps 20 Hz (its speed loop is 5 Hz).

    Parameters
    ----------
    sc : Scenario
        The scenario.
    mras : MrasSettings, optional
        The MRAS's settings (default ``sc.mras``).

    Returns
    -------
    float
        Bandwidth, Hz.
    """
    mras = sc.mras if mras is None else mras
    if mras.bandwidth_Hz is not None:
        return mras.bandwidth_Hz
    return max(MRAS_BANDWIDTH_HZ, MRAS_PER_SPEED_BANDWIDTH * speed_bandwidth_Hz(sc))


def mras_type2(sc, mras, T2_hat: float) -> bool:
    """Whether the MRAS of scenario ``sc`` runs the type-2 adaptation: ``acceleration_tracking``
    as set, or by default when the speed reference takes the drive into field weakening
    (:func:`imdrive.config.mras_type.mras_type2_for_field_weakening`) or when
    :func:`~imdrive.config.mras_type.mras_ramp_lag_pu` exceeds
    :data:`~imdrive.config.mras_type.MRAS_RAMP_LAG_MAX_PU`."""
    if mras.acceleration_tracking is not None:
        return mras.acceleration_tracking
    if mras_type2_for_field_weakening(sc):
        return True
    return mras_ramp_lag_pu(sc, mras_bandwidth_Hz(sc, mras), T2_hat) > MRAS_RAMP_LAG_MAX_PU


def r1_max_freq_Hz(mras, f_rated: float) -> float:
    """The online R1 law's upper stator-frequency bound, Hz: ``mras.R1_max_freq_Hz``, or
    ``mras.R1_max_freq_pu`` times the machine's rated frequency ``f_rated`` (Hz): 30 Hz on
    Table IV and the 60 Hz Krause machines, 25 Hz on the 50 Hz ones."""
    if mras.R1_max_freq_Hz is not None:
        return mras.R1_max_freq_Hz
    return mras.R1_max_freq_pu * f_rated


def mras_normalise(sc, mras=None) -> bool:
    """Whether the MRAS normalises its error by the flux reference squared: ``mras.normalise``
    when set, else on exactly with the field weakening (set or by default)."""
    from imdrive.config.field_weakening import field_weakening_on

    mras = sc.mras if mras is None else mras
    return mras.normalise if mras.normalise is not None else field_weakening_on(sc)
