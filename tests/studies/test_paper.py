"""The paper's reproduction: Figs. 5 and 6, and a test of its central claim.

The compensation presets run here at full length (they take well under a second each): the
assertions are the directions of R2_hat's motion and the bounds the full-length runs meet,
including the documented failure of the paper's compensator.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from imdrive import analysis
from imdrive.cli import main
from imdrive.config.machine import machine_preset
from imdrive.config.scenario import Scenario
from imdrive.run.simulate import simulate
from imdrive.studies import paper

MACHINE = machine_preset("paper-table-iv")
R2 = MACHINE.R2_ohm


def _run(name, *overrides):
    res = simulate(Scenario.read(name, list(overrides)))
    assert not res.diverged
    return res, res.compensation_metrics()


# ---------------------------------------------------------------------------------------------
# the injection compensator reaches 2 % within 10 s from +-20 % at 150 and 1000 rpm


@pytest.mark.parametrize(
    "name",
    ["injection-fig5", "injection-fig6", "injection-fig5-150rpm", "injection-fig6-150rpm"],
)
def test_injection_compensator_converges(name):
    res, m = _run(name)
    r2 = res["R2_hat_ohm"]
    t = res.time_s
    start = m["R2_hat_initial_ohm"]
    # direction: every decision moves R2_hat towards R2 until it is within 2 %. A law may then
    # overshoot by up to 2.8 % (the adaptive law of earlier releases did, on the fig6 presets)
    # before it settles; the table law of the first release never passed 2 %.
    # Steps below 0.1 mohm are the thermal model's modelled heating while a decision is held.
    active = r2[t >= 4.0]
    err = np.abs(active / R2 - 1)
    first_in = int(np.argmax(err < 0.02))
    assert err[first_in] < 0.02
    steps = np.diff(active[: first_in + 1])
    decisions = steps[np.abs(steps) > 1e-4]
    assert len(decisions) > 0
    assert np.all(np.sign(decisions) == np.sign(R2 - start))
    assert np.all(err[first_in:] < 0.03)
    # never farther than at the start, but for the thermal model's modelled heating (the
    # plant of these presets does not heat): +0.1 % from the load step to the first decision
    assert np.all(err <= abs(start / R2 - 1) + 0.0015)
    # the targets: within 2 % in under 10 s
    assert m["time_to_tolerance_s"] is not None and m["time_to_tolerance_s"] < 10.0
    assert abs(m["R2_hat_final_error_pct"]) < 2.0
    assert abs(m["speed_error_after_rpm"]) < 1.0
    assert m["speed_ripple_after_rpm"] < 5.0
    # and it fixed what the R2 error had cost
    assert abs(m["speed_error_before_rpm"]) > 10.0


def test_injection_compensator_shortened_direction():
    """One second of compensation already moves R2_hat the right way, within its bounds."""
    res, m = _run("injection-fig5", "simulation.t_end_s=5.6")
    assert R2 < m["R2_hat_final_ohm"] < m["R2_hat_initial_ohm"]


# ---------------------------------------------------------------------------------------------
# the paper's compensator: what it really does


@pytest.mark.parametrize("name", ["paper-fig5", "paper-fig6", "paper-fig6-150rpm"])
def test_paper_compensator_follows_the_sampling_bias_down(name):
    """e_d0 is negative in steady state whatever R2_hat is, so R2_hat only ever decreases.

    From +20 % that first helps, then overshoots; from -20 % it goes the wrong way. Both end far
    from R2 (measured: at the 0.5 R2 clamp after 7 s at 1000 rpm).
    """
    res, m = _run(name)
    r2 = res["R2_hat_ohm"]
    t = res.time_s
    assert m["e_d0_mean_after_Wb"] < 0
    assert r2[-1] < m["R2_hat_initial_ohm"]
    assert np.all(r2 >= 0.408 - 1e-12)  # the clamp holds
    assert m["time_to_tolerance_s"] is None
    assert abs(m["speed_error_after_rpm"]) > abs(m["speed_error_before_rpm"])
    assert np.all(r2[t < 4.0] == m["R2_hat_initial_ohm"])


def test_paper_compensator_shortened_direction():
    res, m = _run("paper-fig6", "simulation.t_end_s=5.0")
    assert m["R2_hat_final_ohm"] < m["R2_hat_initial_ohm"]  # away from R2: the claim fails


# ---------------------------------------------------------------------------------------------
# the central claim, measured


def test_steady_state_e_d0_has_no_R2_information():
    """The paper: sign(e_d0) = sign(R2 - R2_hat) in steady state. Measured: e_d0 is the same
    (a negative sampling bias) for R2_hat 20 % low and 20 % high, and shrinks as Ts^2."""
    df = paper.e_d0_versus_Ts(Ts=(1e-4, 5e-5), ratios=(0.8, 1.2), speeds=(1000.0,))
    for _, g in df.groupby("Ts_s"):
        low, high = g.sort_values("R2_ratio")["e_d0_Wb"].to_numpy()
        assert low < 0 and high < 0  # the paper expects low > 0
        assert abs(high - low) < 0.1 * abs(low)
    big = df[df["Ts_s"] == 1e-4]["e_d0_Wb"].to_numpy()
    small = df[df["Ts_s"] == 5e-5]["e_d0_Wb"].to_numpy()
    ratio = big / small
    assert np.all((ratio > 3.5) & (ratio < 4.5))  # halving Ts divides it by four


def test_injection_signal_changes_sign_at_R2():
    df = paper.injection_signal(ratios=(0.8, 1.0, 1.2), speeds=(1000.0,))
    d = df.set_index("R2_ratio")["demodulated_Wb"]
    assert d[0.8] > 0 > d[1.2]
    assert abs(d[1.0]) < 0.05 * min(abs(d[0.8]), abs(d[1.2]))


# ---------------------------------------------------------------------------------------------
# steady-state analysis agrees with the simulation within 1 %


@pytest.mark.parametrize(
    ("speed_rpm", "load_Nm", "ratio"), [(1000.0, 12.0, 1.2), (150.0, 6.0, 0.8), (500.0, 9.0, 1.0)]
)
def test_foc_operating_point_matches_simulation(speed_rpm, load_Nm, ratio):
    op = analysis.foc_operating_point(MACHINE, speed_rpm, load_Nm, R2_ratio=ratio)
    res = paper.sensorless_run(speed_rpm, load_Nm, ratio)
    w = res.window(res.time_s[-1] - 0.5)
    v_mag = np.hypot(w["v_alpha_V"], w["v_beta_V"])
    sim = {
        "speed_rpm": np.mean(w["speed_rpm"]),
        "id_A": np.mean(w["i_d_A"]),
        "iq_A": np.mean(w["i_q_A"]),
        "psi_r_Wb": np.mean(w["flux_Wb"]),
        "V_s_peak_V": np.mean(v_mag),
        "torque_Nm": np.mean(w["torque_Nm"]),
    }
    for key, value in sim.items():
        assert value == pytest.approx(getattr(op, key), rel=0.01), key
    if ratio != 1.0:
        err = sim["speed_rpm"] - speed_rpm
        assert err == pytest.approx(op.speed_error_rpm, rel=0.01)


# ---------------------------------------------------------------------------------------------
# imdrive paper


@pytest.mark.slow
def test_cli_paper_regenerates_everything(tmp_path, capsys):
    out = tmp_path / "paper"
    assert main(["paper", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "[15/15]" in err  # progress indication
    pngs = {p.name for p in out.glob("*.png")}
    assert {f"{n}.png" for n in paper.COMPENSATION_PRESETS} <= pngs
    assert {
        "e_d0_vs_R2_ratio.png",
        "e_d0_vs_Ts.png",
        "e_d0_vs_R1.png",
        "injection_signal.png",
        "e_d0_transients.png",
        "detuning_law.png",
        "thermal_tracking.png",
    } <= pngs
    results = json.loads((out / "results.json").read_text())
    rows = {r["preset"]: r for r in results["compensation"]}
    assert rows["paper-fig5"]["time_to_tolerance_s"] is None
    assert rows["injection-fig6"]["time_to_tolerance_s"] < 10.0
    assert results["thermal_tracking"]["max_R2_error_pct_during_ramp"] < 5.0
