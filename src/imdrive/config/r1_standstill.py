"""The drive's standstill R1 identification in a scenario (``mras.R1_standstill``,
``mras.R1_standstill_levels``; kernels/r1_standstill.py): how many current levels it uses, and
its parameters (:func:`r1_standstill_fields`). The settings keep their ``[mras]`` names, where
the test began; it is the controller's and runs whatever the speed estimator.

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


def r1_standstill_fields(sc, R1_hat: float, T2_hat: float) -> dict:
    """The standstill test's fields of ``CONTROL_PARAMS`` (kernels/r1_standstill.py
    ``R1_STANDSTILL_PARAMS``).

    Parameters
    ----------
    sc : Scenario
        The scenario (``mras.R1_standstill``, ``R1_standstill_levels``,
        ``R1_standstill_first_level``, ``R1_standstill_hold_T2``).
    R1_hat : float
        The controller's R1_hat at the start, ohm: the identified value is clamped to
        ``[0.5, 2] R1_hat``.
    T2_hat : float
        The controller's rotor time constant ``L2_hat / R2_hat`` at the start, s.

    Returns
    -------
    dict
        ``R1_dc``, ``R1_dc_settle``, ``R1_dc_block``, ``R1_dc_nT2``, ``R1_dc_levels``,
        ``R1_dc_boost``, ``R1_dc_hold``, ``R1_dc_min``, ``R1_dc_max``.
    """
    mras = sc.mras
    return dict(
        R1_dc=mras.R1_standstill,
        # the window opens 3.5 rotor time constants, measured on the flux build-up (blocks
        # of a quarter of the controller's T2_hat), into the run
        R1_dc_settle=T2_hat,
        R1_dc_block=0.25 * T2_hat,
        R1_dc_nT2=3.5,
        R1_dc_levels=r1_standstill_levels(sc),
        R1_dc_boost=mras.R1_standstill_first_level - 1.0,
        R1_dc_hold=mras.R1_standstill_hold_T2 * T2_hat,
        R1_dc_min=0.5 * R1_hat,
        R1_dc_max=2.0 * R1_hat,
    )
