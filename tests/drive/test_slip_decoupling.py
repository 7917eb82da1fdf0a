"""The slip's coupling of the MRAS's q-axis flux error into the detected R2 signal, and its removal.

Mechanism (kernels/detection.py ``slip_coupling``, docs/envelope.md): in the controller's
frame the rotor's d flux is driven by ``w_s psi_q``; the adjustable model is held on the d axis,
so the q-axis error the MRAS's finite bandwidth leaves through the injection's torque ripple
reaches the d-axis error through ``w_s T2/(1 + s T2)``. At full load above base speed
(``w_s T2 = i_q/i_d``, 3-5) that is of the size of the R2 signal, of the sign of the slip:
motoring with the torque the machine delivers there, R2_hat ends 33 % off on Table IV at 1.5 x
the rated speed from R2_hat(0) = 1.3 R2, and drifts 28 % low on Krause's 3 hp machine at twice
the rated speed from R2_hat(0) = R2; with the correction both end within 0.1 %. (On the Aalto
2.2 kW machine the part is small: within 0.15 % either way at 1.5 x.) The speed error falls with
R2_hat's; at twice the rated speed 2.4 rpm remain (0.07 % of the speed), a second-order
discretisation residual of the 100 us control period (1.5 rpm less at 50 us).

The runs pin the type-1 MRAS, with which the mechanism was measured: the type-2 loop, the
default now when the drive goes into field weakening (config/mras_type.py), leaves a far
smaller q-axis error to couple (without the correction, measured 0.00 % on Table IV and
-0.99 % on Krause 3 hp, the latter flagged `speed-error`, before the compensator's speed gate
weighed the speed error by the loop's gain; since, +0.47 %, 1.9 rpm, still `speed-error`;
with it both within 0.01 %).
That last run also pins the PI current controller: with the internal-model controller, the
default at twice the rated speed (kernels/current_control.py), the current follows its
reference closely enough that without the correction R2_hat ends -0.03 % off (within goal).
"""

from __future__ import annotations

import pytest
from data.ramp import ramp_scenario

from imdrive import simulate_batch

pytestmark = pytest.mark.slow  # end to end: 6 closed-loop runs of 24 s


def _runs(
    machine: str,
    speed_pu: float,
    R2_ratio: float,
    type1: bool = True,
    pi: bool = False,
    fixed_gains: bool = False,
):
    """The run without and with the correction; ``type1`` pins the type-1 MRAS, ``pi`` the PI
    current controller, ``fixed_gains`` the speed PI's designed gains in field weakening."""
    pinned = {"mras.acceleration_tracking": False} if type1 else {}  # the whole coupling
    if pi:
        pinned["control.current_controller"] = "pi"
    if fixed_gains:
        pinned["control.speed_gain_flux_scaling"] = False
    scs = [
        ramp_scenario(
            machine,
            speed_pu,
            {
                "injection.decouple_slip": on,
                "estimator.R2_ratio": R2_ratio,
                "estimator.R1_ratio": 1.0,
                "simulation.t_end_s": 24.0,
            }
            | pinned,
            load_pu_available=1.0,
        )
        for on in (False, True)
    ]
    off, on = simulate_batch(scs).metrics.itertuples()
    return {False: off, True: on}


@pytest.mark.parametrize("machine, speed_pu, R2_ratio", [("krause-3hp", 2.0, 1.0)])
def test_decoupling_with_the_default_type2_loop(machine, speed_pu, R2_ratio):
    # with the speed gains scaled by the flux factor (the default in field weakening) the run
    # without the correction ends within goal too (R2_hat +0.06 %, 0.19 rpm): pinned off, the
    # loop it was measured on. With the adaptive law of earlier releases the run without the
    # correction ended +0.47 % off (out of goal); the Kalman law, which weighs each window by
    # its noise instead of stepping on it, ends -0.026 % without it and +0.001 % with it: the
    # correction is no longer what holds this point
    r = _runs(machine, speed_pu, R2_ratio, type1=False, pi=True, fixed_gains=True)
    off, on = r[False], r[True]
    assert off.verdict == "ok" and abs(off.R2_error_pct) < 0.1  # measured -0.026 %
    assert on.verdict == "ok" and abs(on.R2_error_pct) < 0.02  # measured 0.001 %
    assert abs(on.R2_error_pct) < abs(off.R2_error_pct)


@pytest.mark.parametrize(
    "machine, speed_pu, R2_ratio", [("paper-table-iv", 1.5, 1.3), ("krause-3hp", 2.0, 1.0)]
)
def test_decoupling_removes_the_bias_at_full_load_above_base_speed(machine, speed_pu, R2_ratio):
    r = _runs(machine, speed_pu, R2_ratio)
    off, on = r[False], r[True]
    assert abs(off.R2_error_pct) > 10.0  # the mechanism: biased without the correction
    assert off.verdict != "ok"  # and flagged
    assert abs(on.R2_error_pct) < 0.5
    # what remains of the speed error is the discretisation residual (module docstring): a
    # few hundredths of the rated slip
    assert abs(on.speed_error_pu_slip) < 0.05
