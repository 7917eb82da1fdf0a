"""Whether the speed PI's gains follow the field weakening's flux factor
(``control.speed_gain_flux_scaling``; kernels/speed_control.py).

A sensorless estimator's speed error from a wrong R2_hat is ``-(R2_hat/R2 - 1) w_s``, the slip
``w_s`` proportional to ``i_q/psi``: through the speed PI a positive feedback of the torque
current whose loop gain grows as the flux falls. With the measured speed there is none, and the
gains stay as designed.
"""

from __future__ import annotations

from imdrive.config.field_weakening import field_weakening_on


def speed_gain_flux_scaling(sc) -> bool:
    """``control.speed_gain_flux_scaling`` if set, else whether field weakening is on
    (:func:`~imdrive.config.field_weakening.field_weakening_on`) and the speed feedback an
    estimate (``control.speed_feedback`` other than ``"measured"``).

    Parameters
    ----------
    sc : Scenario

    Returns
    -------
    bool
    """
    given = sc.control.speed_gain_flux_scaling
    if given is not None:
        return bool(given)
    return field_weakening_on(sc) and sc.control.speed_feedback != "measured"
