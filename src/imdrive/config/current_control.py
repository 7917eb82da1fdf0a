"""The current controller by default (``control.current_controller``): the internal-model
controller (kernels/current_control.py) when the drive goes deep into field weakening, the PIs
with the cross-coupling taken at the references otherwise.

The PIs' weakness grows with the synchronous speed over the loop's bandwidth, ``w_e / a_c``
(``w_e sigma_L1`` against ``kp = a_c sigma_L1``, and the back-emf, nearly all of the voltage,
rejected only at ``R_sigma/sigma_L1``): 0.44 at 1.5 x and 0.58 at 2 x the rated speed on
Table IV with the 200 Hz loop. The internal-model controller is the default from
:data:`IMC_FROM_PU_OF_BANDWIDTH` of it. Measured (the whole-rating envelope's cells, R1_hat
0.9 R1, constant R2, 30 cells per speed sign and inverter): at +-2 x on Table IV within goal
20 -> 22 on the ideal drive, 15 -> 21 on the dead-time bridge; at +-1.5 x it was no better
(Table IV: the same counts, two cells of the bridge traded; Krause 3 hp: the two cells from
1.3 R2 at the available torque regenerating went from within goal to held, the sensorless
loop's oscillation from a wrong R2_hat that the PIs' softer current loop damped); at 0.1 x
and 20 rpm it lost two cells of the ideal drive. Below that speed the presets keep the PIs and
their results bit for bit.
"""

from __future__ import annotations

import math

from imdrive.config.field_weakening import field_weakening_on
from imdrive.config.rated import rated_point_or_none

#: The internal-model controller is the default where the speed reference's electrical speed
#: reaches this fraction of the current loop's bandwidth (with field weakening on).
IMC_FROM_PU_OF_BANDWIDTH = 0.5


def current_controller(sc) -> str:
    """``control.current_controller``, or by default ``"imc"`` where field weakening is on
    (:func:`~imdrive.config.field_weakening.field_weakening_on`: set, or by default) and
    the speed reference's peak electrical speed ``n_p |w_m|`` exceeds
    :data:`IMC_FROM_PU_OF_BANDWIDTH` times the current loop's bandwidth (rad/s), else ``"pi"``
    (also without a rated point).

    Parameters
    ----------
    sc : Scenario

    Returns
    -------
    str
        ``"pi"`` or ``"imc"``.
    """
    ctl = sc.control
    if ctl.current_controller is not None:
        return ctl.current_controller
    if not field_weakening_on(sc) or rated_point_or_none(sc.machine) is None:
        return "pi"
    from imdrive.config.profile_units import stated_speed_ref_rpm

    w_e = sc.machine.pole_pairs * stated_speed_ref_rpm(sc).peak * math.pi / 30.0
    a_c = 2.0 * math.pi * ctl.current_bandwidth_Hz
    return "imc" if w_e > IMC_FROM_PU_OF_BANDWIDTH * a_c else "pi"
