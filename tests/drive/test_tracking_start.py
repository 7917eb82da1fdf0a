"""R2 tracking starts in the duty cycle's time (issue 38, round 7): ``compensator.t_on_s``, and
its injection with it, moves with the speed and load profiles when the drive's sequence
delays them, by the premagnetisation (config/sequence.py) and by the standstill R1 test's
wait (kernels/stages.py, ``t_hold``); on Table IV neither delays it, and the start is the
stated float. Before, the start stayed at its absolute time: on Krause 2250 hp
``injection-robust``'s compensator (4 s) started 1.7 s before the speed reference left zero
(5.67 s), where the preset has it 3.5 s after.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from imdrive.analysis.nameplate import Nameplate, estimate_circuit
from imdrive.analysis.nameplate_cli import machine_toml
from imdrive.config.scenario import Scenario
from imdrive.config.sequence import first_move_s, sequence
from imdrive.run.build import build_arrays
from imdrive.run.compensator_blocks import tracking_start_s
from imdrive.run.metrics import compensator_start_s
from imdrive.run.simulate import simulate

T_ON = 1.5  # the start asked for: 1 s after the preset's speed ramp leaves zero at 0.5 s

#: the 22 kW, 400 V catalogue motor of issue 39
MOTOR_22KW = dict(power_W=22e3, voltage_V=400, frequency_Hz=50, poles=4, speed_rpm=1470,
                  current_A=40.0, power_factor=0.84, efficiency=0.93)  # fmt: skip


@pytest.fixture(scope="module")
def machines(tmp_path_factory) -> dict[str, list[str]]:
    plate = Nameplate(**MOTOR_22KW)
    path = tmp_path_factory.mktemp("machines") / "motor-22kw.toml"
    path.write_text(machine_toml(estimate_circuit(plate, method="catalogue"), plate))
    return {
        "paper-table-iv": [],
        "krause-2250hp": ['machine.preset="krause-2250hp"'],
        "22kw": [f'machine.file="{path}"'],
    }


def _scenario(machine: list[str]) -> Scenario:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (a machine file's values stay as its own)
        return Scenario.read(
            "injection-robust",
            [
                *machine,
                f"compensator.t_on_s={T_ON}",
                "simulation.t_end_s=4",
                "simulation.log_every=1",
            ],
        )


@pytest.mark.parametrize("name", ["paper-table-iv", "krause-2250hp", "22kw"])
def test_the_start_moves_with_the_premagnetisation_as_the_profiles_do(machines, name):
    sc = _scenario(machines[name])
    seq = sequence(sc)
    comp = build_arrays(sc).params.comp[0]
    assert comp["t_on"] == comp["inj_t_on"] == tracking_start_s(sc) == T_ON + seq.delay_s
    # the start keeps its place in the duty cycle: as far after the speed's first move
    assert first_move_s(seq.speed_ref_rpm) == pytest.approx(0.5 + seq.delay_s, abs=1e-12)
    if name == "paper-table-iv":
        assert seq.delay_s == 0.0 and comp["t_on"] == T_ON  # the same float
    else:
        assert seq.delay_s > 0.3  # 3 T2_hat(0) of premagnetisation: 3.5 s, 0.34 s


@pytest.mark.parametrize("name", ["paper-table-iv", "krause-2250hp", "22kw"])
def test_the_start_waits_for_the_standstill_r1_test_as_the_profiles_do(machines, name):
    sc = _scenario(machines[name])
    res = simulate(sc)
    t, Ts = res.time_s, sc.simulation.Ts_s
    moved = int(np.argmax(res["speed_ref_rpm"] != 0.0))  # the reference's first move
    t_ref = t[moved - 1]
    comp = res.state_final.comp[0]
    t_hold = float(res.state_final.model[0]["t_hold"])
    assert comp["on"]
    t_start = float(comp["t_start"])
    # where the duty cycle put it: as long after the reference's first move as stated
    assert t_start - t_ref == pytest.approx(T_ON - 0.5, abs=1.5 * Ts)
    assert t_start == pytest.approx(T_ON + sequence(sc).delay_s + t_hold, abs=1.5 * Ts)
    # the injection starts with it (its detected product is 0 before: sin(0) at the start)
    injected = t[np.argmax(res["e_d0_demod_Wb"] != 0.0)]
    assert injected == pytest.approx(t_start + Ts, abs=0.5 * Ts)
    # the metrics count the compensator's time from there
    assert compensator_start_s(res) == t_start
    if name == "paper-table-iv":
        assert t_hold == 0.0 and t_start == T_ON
    else:  # the sequence moved it 0.9 s (22 kW) and 5.2 s (Krause 2250 hp) later
        assert t_hold > 0.3 and t_start - T_ON > 0.8


def test_injection_t_on_s_is_deprecated_and_the_injection_starts_with_the_compensator():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sc = Scenario.read("injection-robust", ["injection.t_on_s=2.0"])
    notes = [str(w.message) for w in caught if str(w.message).startswith("injection.t_on_s")]
    assert len(notes) == 1 and "starts with the compensator" in notes[0]
    comp = build_arrays(sc).params.comp[0]
    assert comp["inj_t_on"] == comp["t_on"] == 4.0  # compensator.t_on_s, as every preset had
