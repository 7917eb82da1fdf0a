"""The recommended preset on a library machine, ramped to a per-unit speed: the scenario the
drive tests of the compensator's whole-range mechanisms share (as the whole-rating envelope
runs it, docs/envelope.md)."""

from __future__ import annotations

from imdrive import Scenario
from imdrive.config.rated import rated_point
from imdrive.sweep.model import available_torque_Nm

#: The whole-rating envelope's switching bridge: 2 us of dead time compensated as 1.6 us
BRIDGE = {
    "inverter.model": "switching",
    "inverter.dead_time_s": 2e-6,
    "control.dead_time_compensation": "feedforward",
    "control.dead_time_compensation_s": 1.6e-6,
}


def ramp_scenario(
    machine: str, speed_pu: float, overrides: dict, *, load_pu_available: float | None = None
) -> Scenario:
    """``injection-robust`` on ``machine`` (its model-based R2 law) on the MRAS, the estimator
    these mechanisms were built and measured on (the preset runs the adaptive observer since
    2026-11-30; ``overrides`` may set ``control.speed_feedback``): the
    speed reference ramped from 0.5 s over 3 s to ``speed_pu`` x the rated speed, injection
    and compensator from 5 s, then ``overrides``;
    with ``load_pu_available`` a load step at 4 s to that fraction of the torque the machine
    delivers at that speed (:func:`imdrive.sweep.model.available_torque_Nm`)."""
    base = Scenario.read(
        "injection-robust", [f'machine.preset="{machine}"', 'control.speed_feedback="mras"']
    )
    rp = rated_point(base.machine)
    sc = base.with_overrides(
        {
            "control.speed_ref_rpm": {
                "initial": 0,
                "changes": [{"at": 0.5, "to": speed_pu * rp.speed_rpm, "over": 3.0}],
            },
            "compensator.t_on_s": 5.0,
        }
        | overrides
    )
    if load_pu_available is None:
        return sc
    T = load_pu_available * available_torque_Nm(sc)
    load = {"initial": 0, "changes": [{"at": 4.0, "to": T}]}
    return sc.with_overrides({"load.torque_Nm": load})
