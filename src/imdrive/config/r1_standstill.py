"""How many current levels the standstill R1 identification uses in a scenario
(``mras.R1_standstill_levels``; kernels/estimators/mras_standstill.py).

Two levels separate R1 from the residual the controller's inverter-error compensation leaves
(and start the compensation's online scale from it), at the cost of 3-4.5 rotor time
constants more magnetisation, which the duty cycle waits for. A controller that believes
its inverter ideal (no dead-time compensation, no inverter-error table) has neither a
residual to separate nor a scale to start: one level there, so the ideal drive keeps its
timeline.
"""

from __future__ import annotations

from typing import Annotated

from imdrive.config.validation import Float, setting

#: ``mras.R1_standstill_hold_T2``
StandstillHold = Annotated[
    Float,
    setting(
        "longest the first start's premagnetisation is extended for the standstill test "
        "(two levels: the test; one level: its window of half a T̂2 after the measured flux "
        "build-up), per unit of T̂2(0); the duty cycle, speed reference and load, waits "
        "(config/sequence.py); 0: it does not wait",
        ge=0.0,
    ),
]


def r1_standstill_levels(sc) -> int:
    """``mras.R1_standstill_levels`` as set, else 2 where the controller compensates its
    inverter's voltage error (``control.dead_time_compensation = "feedforward"`` or a
    ``[controller_model]`` inverter-error table), else 1.

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    int
        1 or 2.
    """
    if sc.mras.R1_standstill_levels is not None:
        return sc.mras.R1_standstill_levels
    compensates = sc.control.dead_time_compensation == "feedforward"
    return 2 if compensates or sc.controller_model.uses_inverter_error else 1
