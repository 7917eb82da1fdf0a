"""Issue 38, "held without cause": on a slow rotor the model-based law's settling after the
injection starts costs rotor time constants, not whole decision windows.

The 22 kW catalogue motor (``imdrive machine-from-nameplate`` from 22 kW, 400 V, 50 Hz, 4
poles, 1470 rpm, 40.5 A, cos phi 0.84, eta 0.92, T_bd/T_n 2.8, I_st/I_n 7.3: T2 = 0.36 s, the
injection at 0.48 Hz, 2.08 s windows) under ``injection-robust`` at 1000 rpm and rated load
from 2 s, the compensator from 4 s. On the grid the first update came at 12.5/10.0/8.3 s from
R2_hat(0) = 0.8/1.0/1.2 R2 (a partial window, an empty one and a held one); measured with the
settling in time: 8.49/7.59/6.99 s, R2_hat held 44.9/35.9/29.9 % of the time since the
compensator's start, R2_hat at 14 s within 0.05 %.
"""

from __future__ import annotations

import numpy as np
import pytest

from imdrive import Scenario, simulate
from imdrive.config.rated import rated_point

M22 = """[machine]
R1_ohm = 0.10999212218181809
R2_ohm = 0.11963307491753046
Ll1_H = 0.0017316424606880463
Ll2_H = 0.0017316424606880463
M_H = 0.04180310146567572
pole_pairs = 2
J_kgm2 = 0.155
B_Nms = 0.0
rated_power_W = 22000.0
rated_voltage_V = 400.0
rated_frequency_Hz = 50.0
rated_speed_rpm = 1470.0
rated_current_rms_A = 40.5
rated_power_factor = 0.84
rated_efficiency = 0.92
"""


@pytest.mark.slow
@pytest.mark.parametrize(
    ("ratio", "held_max", "first_max"), [(0.8, 50.0, 9.0), (1.2, 35.0, 7.5)]
)  # measured 44.9 % / 8.49 s and 29.9 % / 6.99 s; the grid: 62.5 % / 12.5 s, 41.6 % / 8.33 s
def test_slow_rotor_is_held_rotor_time_constants_not_windows(tmp_path, ratio, held_max, first_max):
    f = tmp_path / "m22.toml"
    f.write_text(M22)
    base = Scenario.read("injection-robust", [f'machine.file="{f}"'])
    T = rated_point(base.machine).torque_Nm
    sc = base.with_overrides(
        {
            "estimator.R2_ratio": ratio,
            "control.speed_ref_rpm": {
                "initial": 0,
                "changes": [{"at": 0.5, "to": 1000, "over": 1.0}],
            },
            "load.torque_Nm": {"initial": 0, "changes": [{"at": 2.0, "to": T}]},
        }
    )
    res = simulate(sc)
    m = res.metrics()
    t = res.time_s
    on = t >= sc.compensator.t_on_s
    live = np.asarray(res["comp_live_flag"])[on]
    first = t[on][np.argmax(live > 0)]
    assert live.any() and first < first_max
    assert m["R2_held_pct"] < held_max
    # only the settling held it (bit 8): no whole window more (16), the load is constant
    assert int(m["R2_held_causes"]) == 8
    assert abs(m["R2_error_pct"]) < 1.0
