"""The MRAS's adaptation type by default, from the machine and the scenario: the type-1 loop
(:func:`imdrive.design.gains.default_mras_gains`) or the type-2 loop
(:func:`imdrive.design.gains.mras_type2_gains`), whichever the drive needs to follow its
accelerations (:func:`imdrive.config.estimators.mras_type2` decides).
"""

from __future__ import annotations

import math

from imdrive.config.field_weakening import field_weakening_on
from imdrive.config.rated import rated_point_or_none as _rated_point_or_none

#: The type-1 MRAS's lag at the machine's rated acceleration, in units of the rotor's corner
#: frequency 1/T2, above which the MRAS runs its type-2 adaptation by default
#: (:func:`mras_ramp_lag_pu`): at half the corner frequency the error signal's gain has fallen
#: by a fifth (``x / (1 + x^2)`` against ``x``).
MRAS_RAMP_LAG_MAX_PU = 0.5

#: The type-2 adaptation is also on by default when the speed reference goes above this
#: multiple of the rated speed with field weakening on (:func:`mras_type2_for_field_weakening`).
MRAS_TYPE2_ABOVE_PU = 1.1


def mras_ramp_lag_pu(sc, bandwidth_Hz: float, T2_hat_s: float) -> float:
    """The type-1 MRAS's lag behind the machine's rated acceleration, over ``1/T2``.

    The MRAS with its PI adaptation is a first-order tracker of bandwidth ``a`` (rad/s,
    :func:`imdrive.design.gains.default_mras_gains`): under a constant acceleration ``alpha``
    (electrical rad/s^2) its estimate lags by ``alpha / a``. Its error signal is linear in
    the speed error only within the rotor's corner frequency ``1/T2`` (``e ~ x / (1 + x^2)``,
    ``x = T2 dw``), and the indirect field orientation running on the estimate misplaces its
    slip by the lag, so the lag is stated in that unit, at the acceleration the rated torque
    gives the machine's inertia (``alpha = n_p T_rated / J``)::

        lag_pu = n_p (T_rated / J) T2 / a

    Library: Table IV 0.25, Krause 3 hp 0.19, 50 hp 0.31, 500 hp 2.3, 2250 hp 3.6, the
    2.2 kW Aalto machine 1.7, the 3.3 kV machine 2.1 (20 Hz). Without a rated point: 0.

    Parameters
    ----------
    sc : Scenario
        The scenario (its machine: rated torque, inertia, pole pairs).
    bandwidth_Hz : float
        The MRAS's bandwidth ``a / (2 pi)``, Hz.
    T2_hat_s : float
        The estimator's rotor time constant, s.

    Returns
    -------
    float
        Dimensionless.
    """
    m = sc.machine
    rp = _rated_point_or_none(m)
    if rp is None or m.J_kgm2 <= 0.0:
        return 0.0
    alpha_e = m.pole_pairs * rp.torque_Nm / m.J_kgm2
    return alpha_e * T2_hat_s / (2.0 * math.pi * bandwidth_Hz)


def mras_type2_for_field_weakening(sc) -> bool:
    """Whether the scenario runs its drive into field weakening, where the type-1 MRAS's
    gain collapses: field weakening on and the speed reference somewhere above
    :data:`MRAS_TYPE2_ABOVE_PU` times the rated speed.

    The adaptation loop's gain at low frequency is ``|lam|^2 T2 / (1 + x^2)``, ``x = w_s T2``
    the slip per-unit of the rotor's corner frequency (the current model's response to a
    speed error, its part across the flux). The flux normalisation holds the ``|lam|^2``
    part, but accelerating in field weakening at the current limit the slip rises as the flux
    falls (``x = M iq / psi``: 13 on Table IV at twice the rated speed), and the type-1
    loop's lag behind the ramp with it: measured at twice the rated speed on Table IV, 14 rpm
    at 1.5 s, 56 at 2.5 s, 170 at 2.7 s, after which the speed ran 340 rpm over its
    reference and the voltage limit left the controller's frame 90 degrees off the flux (on
    the dead-time bridge every run of the whole-rating envelope at twice the rated speed
    lost control). The type-2 loop has no steady lag behind an acceleration whatever its gain
    (:func:`imdrive.design.gains.mras_type2_gains`). Decided on the scenario's speed
    reference rather than switched at run time: holding and releasing the second integral at
    the rated frequency, where the loaded drive sits, lost control at rated speed and load.

    Parameters
    ----------
    sc : Scenario
        The scenario (``control.field_weakening``, ``control.speed_ref_rpm``, the machine's
        rated speed).

    Returns
    -------
    bool
    """
    if not field_weakening_on(sc):
        return False
    rp = _rated_point_or_none(sc.machine)
    if rp is None:
        return False
    from imdrive.config.profile_units import stated_speed_ref_rpm

    return stated_speed_ref_rpm(sc).peak > MRAS_TYPE2_ABOVE_PU * rp.speed_rpm
