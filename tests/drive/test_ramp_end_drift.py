"""The adaptive law follows the end of an R2 ramp without running on (kernels/drift_rate.py,
kernels/sensitivity.py ``fine_loop_gain_ratio``).

Whole-rating envelope cells (sweep envelope-full: the plant's R2 +20 % from 6 s to 36 s, the
run ends at 38 s) from R2_hat(0) = 0.7 R2 on the ideal drive. With the plain law, on Table IV:

* at 2 x rated speed, regenerating the available torque, the drift kept walking R2_hat at
  0.78 of the ramp's rate 1.7 s after the ramp stopped: R2_hat ended +0.93 %, the speed
  2.9 rpm off (tolerance 1.72); on Krause's 3 hp machine +0.93 % and 2.3 rpm (+0.86 % on
  both since the standstill R1 test no longer carries R2_hat(0)'s error);
* at 1.5 x rated speed, motoring, the drift was never integrated (the detected error shrank
  by 0.05 % per decision as the injection's sensitivity fell with T2) and R2_hat lagged the
  ramp by 1.5 % as a type-1 loop, ending -0.74 %, 1.75 rpm off.

The loop gain fell as R2_hat moved from 0.7 R2 to 1.2 R2 (the fine step a share of R2_hat(0),
the injection below the heated rotor's corner): 0.4 of its tuned value. Now every one ends
within 0.5 % and within the speed tolerance; the plain law (the three settings below) is run
beside as the control case.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from data.ramp import ADAPTIVE_LAW

from imdrive import simulate_batch
from imdrive.sweep.spec import parse_sweep, sweep_text

pytestmark = pytest.mark.slow

PLAIN_LAW = [
    "compensator.drift_unwind_factor=1",
    "compensator.drift_shrink_margin=0",
    "compensator.fine_gain_follows_R2=false",
]
#: (machine, speed_pu, load_pu_available): the cells, and the plain law's final R2_hat error, %
CELLS = {
    ("paper-table-iv", 2.0, -1.0): 0.86,
    ("paper-table-iv", 1.5, 1.0): -0.74,
    ("krause-3hp", 2.0, -1.0): 0.86,
}


def _cell(machine: str, speed_pu: float, load_pu: float, extra: list[str]):
    text, folder = sweep_text("envelope-full")
    text = text.replace("[set]\n", f'[set]\nmachine.preset = "{machine}"\n', 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the machine replaced under the sweep's settings
        sweep = parse_sweep(text, folder, "envelope-full")
    want = {
        "speed_pu": speed_pu,
        "load_pu_available": load_pu,
        "R2_ratio": 0.7,
        "R1_ratio": 0.9,
        "thermal": "ramp",
        "inverter": "ideal",
    }
    sc = sweep.scenario_for(tuple(want[a.name] for a in sweep.axes))
    law = [f"{k}={v!r}".replace("'", '"') for k, v in ADAPTIVE_LAW.items()]
    return sc.with_overrides(["simulation.log_every=1000", *law, *extra])


@pytest.fixture(scope="module")
def runs():
    keys = list(CELLS)
    scs = [_cell(*k, []) for k in keys] + [_cell(*k, PLAIN_LAW) for k in keys]
    b = simulate_batch(scs, logs=True)
    n = len(keys)
    rows = list(b.metrics.itertuples())
    return {k: (rows[i], b.results[i], rows[n + i]) for i, k in enumerate(keys)}


@pytest.mark.parametrize("cell", list(CELLS), ids=lambda c: f"{c[0]}-{c[1]}x-load{c[2]:+}")
def test_R2_hat_does_not_run_on_after_the_ramp(runs, cell):
    new, res, plain = runs[cell]
    # the control case: the plain law ran on (or lagged) as measured
    assert plain.R2_error_pct == pytest.approx(CELLS[cell], abs=0.05)
    assert plain.verdict != "ok"
    assert abs(new.R2_error_pct) < 0.5, new.R2_error_pct  # measured 0.13-0.22 %
    assert new.verdict == "ok", new.verdict_text
    t = np.asarray(res["time_s"])
    err = 100.0 * (np.asarray(res["R2_hat_ohm"]) / np.asarray(res["R2_ohm"]) - 1.0)
    # after the ramp stops at 36 s R2_hat does not run on past R2 by more than 0.6 %
    assert err[t >= 36.0].max() < 0.6  # measured 0.47-0.54 %
