"""The online inverter-error scale on a sensorless drive above the rated speed at no load.

Mechanism (kernels/inverter_scale.py, module docstring): the scale used to read the residual
dead-time error's sixth harmonic in the current PIs' output. On a sensorless drive that output
holds a second sixth harmonic of the same origin: the residual enters the MRAS's voltage model,
the speed estimate carries its sixth harmonic, and the speed PI passes it into ``iq*``, which
at light load lies across the current. At 1.5 x the rated speed and no load (Table IV, 2 us
dead time compensated as 1.6 us) that path was 1.3 times the direct one and opposite: the
law's loop gain was -0.42 of its design, the equilibrium ``k = 2/1.6`` unstable, the scale
ran to its bound (0.25) and the standstill-identified R1_hat, which gives the scale's share
back, to 3.3 R1; the speed ended +1.39 rpm off (+1.18 rpm without the R2 injection, as here;
Krause's 3 hp machine the same, +1.17 rpm). The scale now reads the stator voltage equation's
residual over each period, which no controller path reaches: k ends at 1.22 on both (the
bridge's loss has the current ripple's shape, a little less sixth harmonic than the
six-step), R1_hat within 7 % and the speed within 0.01 rpm.
"""

from __future__ import annotations

import pytest

from imdrive import Scenario, simulate
from imdrive.config.rated import rated_point

RATIO = 2.0 / 1.6  # the true dead time over the one the compensation assumes


def _run(machine: str, signal: str | None = None, levels: int | None = None):
    base = Scenario.read("injection-robust", [f'machine.preset="{machine}"'])
    speed = 1.5 * rated_point(base.machine).speed_rpm
    o = {
        "inverter.model": "switching",
        "inverter.dead_time_s": 2e-6,
        "control.dead_time_compensation": "feedforward",
        "control.dead_time_compensation_s": 1.6e-6,
        "estimator.R2_ratio": 1.0,
        "estimator.R1_ratio": 0.9,
        "compensator.enabled": False,
        "injection.amplitude_pu": 0.0,
        "load.torque_Nm": 0.0,
        "control.speed_ref_rpm": {"initial": 0, "changes": [{"at": 0.5, "to": speed, "over": 3.0}]},
        "simulation.t_end_s": 16.0,
        "simulation.log_every": 100,
    }
    if signal is not None:
        o["control.inverter_error_signal"] = signal
    if levels is not None:
        o["mras.R1_standstill_levels"] = levels
    if levels == 1:  # the case of an R1_hat not identified: the start does not wait for it
        o["mras.R1_standstill_hold_T2"] = 0.0
    sc = base.with_overrides(o)
    res = simulate(sc)
    k = 1.0 + res.state_final.control[0]["ie_dk"]
    R1_ratio = res.state_final.model[0]["R1_hat"] / sc.machine.R1_ohm
    return k, R1_ratio, res.metrics()


@pytest.mark.slow  # end to end: 16 s on the switching bridge, per machine
@pytest.mark.parametrize(
    ("machine", "levels", "identified", "R1_end"),
    [
        ("paper-table-iv", None, 1, 1.0),
        ("krause-3hp", None, 1, 1.0),
        # one standstill level, the start not waiting: its window does not open in 0.5 s on the
        # 50 hp machine (by default the start waits for it: test_r1_standstill_wait.py; two
        # levels hold the speed reference until both are identified: test_r1_two_levels.py)
        ("krause-50hp", 1, 2, 0.9),
    ],
)
def test_scale_stable_at_one_and_a_half_rated_speed_sensorless(machine, levels, identified, R1_end):
    # with the current PIs' output: k 0.25 (its bound), R1_hat 3.28 R1, +1.18 / +1.17 rpm on
    # Table IV and Krause's 3 hp machine (the same circuit, another inertia); 5.36 R1 and
    # +0.90 rpm on the 50 hp machine, whose 0.5 s magnetisation is too short for the
    # standstill identification: there R1_hat holds no share of the residual to give back,
    # and taking it out anyway (as k learns) drove R1_hat to its floor, 0.06 R1
    k, R1_ratio, m = _run(machine, levels=levels)
    assert m["R1_id_status"] == identified
    assert k == pytest.approx(RATIO, abs=0.06)
    assert R1_ratio == pytest.approx(R1_end, abs=0.15 if identified == 1 else 0.02)
    assert abs(m["speed_error_rpm"]) < 0.1
