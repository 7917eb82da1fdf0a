"""The estimator bench: its table's numbers are the runs' numbers."""

import math

import numpy as np

from imdrive.bench.metrics import lost_bound_rpm, run_metrics
from imdrive.bench.protocol import CASES, ESTIMATORS, Run, protocol, scenario
from imdrive.bench.report import markdown, run_protocol
from imdrive.run.simulate import simulate


def test_protocol_covers_every_estimator_case_and_drive():
    full = protocol()
    assert len(full) == len(ESTIMATORS) * len(CASES) * 2
    quick = protocol(quick=True)
    assert 0 < len(quick) < len(full) / 5
    for r in quick:
        scenario(r)  # each is a valid scenario


def test_table_metric_recomputed_from_the_runs_log():
    run = Run("mras", "steady-150", "average")
    table, results, _ = run_protocol(runs=[run])
    row = table.iloc[0]
    # the same drive alone, its log, the metric written out by hand
    res = simulate(scenario(run))
    t = res.signals["time_s"]
    w = res.signals["speed_rpm"] - res.signals["speed_ref_rpm"]
    steady = w[t >= t[-1] - 0.5 + 1e-12].mean()
    assert row["steady_speed_error_rpm"] == steady
    est = (res.signals["speed_est_rpm"] - res.signals["speed_rpm"])[t >= t[-1] - 0.5 + 1e-12]
    assert row["speed_est_error_rpm"] == est.mean()
    peak = np.hypot(res.signals["i_alpha_A"], res.signals["i_beta_A"]).max()
    assert row["peak_current_A"] == peak
    assert not row["lost_control"]
    assert f"| steady-150 | {row['steady_speed_error_rpm']:.3g} |" in markdown(table)


def test_lost_control_needs_a_long_excursion():
    t = np.arange(0.0, 3.0, 1e-3)
    ref = np.full_like(t, 100.0)
    sig = {
        "time_s": t,
        "speed_ref_rpm": ref,
        "speed_est_rpm": ref,
        "R2_hat_ohm": np.ones_like(t),
        "R2_ohm": np.ones_like(t),
        "i_alpha_A": np.ones_like(t),
        "i_beta_A": np.zeros_like(t),
    }
    bound = lost_bound_rpm(100.0)
    short = ref.copy()
    short[1000:1200] += 2 * bound  # 0.2 s out
    long_ = ref.copy()
    long_[1000:1400] += 2 * bound  # 0.4 s out
    assert not run_metrics({**sig, "speed_rpm": short}, 0.5, False)["lost_control"]
    assert run_metrics({**sig, "speed_rpm": long_}, 0.5, False)["lost_control"]
    m = run_metrics({**sig, "speed_rpm": ref}, 0.5, True)
    assert m["lost_control"] and math.isnan(m["steady_speed_error_rpm"])
