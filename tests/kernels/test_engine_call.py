"""The engine called through its address (kernels/engine_call.py) runs the same code as a
direct call, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from imdrive.config.scenario import Scenario
from imdrive.kernels.engine import S_OK, run_drive
from imdrive.kernels.engine_call import NO_RECORDING, call_engine, engine_address
from imdrive.run.build import build_arrays, copy_state


@njit
def _through(engine, P, S, n_steps, log):
    return call_engine(
        engine, P, S, np.int64(0), np.int64(n_steps), log, np.int64(1), np.int64(0),
        np.bool_(True), np.zeros(0, dtype=NO_RECORDING.dtype),
    )  # fmt: skip


@pytest.mark.parametrize("preset", ["sensorless", "injection-robust"])
def test_the_address_runs_the_engine_bit_for_bit(preset):
    a = build_arrays(Scenario.read(preset, ["simulation.t_end_s=0.3"]))
    n = a.n_steps
    S1, S2 = copy_state(a.state0), copy_state(a.state0)
    log1, log2 = np.zeros(n + 1, dtype=a.log), np.zeros(n + 1, dtype=a.log)
    st1 = run_drive(a.params, S1, 0, n, log1, 1, 0, True, NO_RECORDING)
    st2 = _through(engine_address(a.params, S2, log2), a.params, S2, n, log2)
    assert st1 == st2
    assert st1[0] == S_OK
    assert log1.tobytes() == log2.tobytes()
    for f1, f2 in zip(S1, S2, strict=True):
        assert f1.tobytes() == f2.tobytes()
