"""Recording and replay (imdrive.run.recording, imdrive.run.replay, kernels/replay.py).

The round trip: a closed-loop run's recording, replayed with the estimator the run used,
gives back the run's speed estimate (and the R2_hat its estimator left) to 1e-9 relative, for
every registered estimator on the average and the realistic drive. Bad input: one line
naming the column or row and the rule, exit 2, nothing written.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import imdrive as im
from imdrive.cli import main
from imdrive.errors import ConfigError
from imdrive.run.recording import REQUIRED, read_recording
from imdrive.run.replay import replay
from imdrive.run.simulate import simulate

#: a short run whose speed moves early, so every estimator has something to track
SHORT = {
    "simulation.t_end_s": 0.3,
    "control.speed_ref_rpm": {"initial": 0, "changes": [{"at": 0.05, "to": 600, "over": 0.2}]},
}
ESTIMATORS = ("mras", "smo-mras", "reactive-mras", "afo", "ekf")
DRIVES = ("sensorless", "sensorless-realistic")


def recorded(preset: str, estimator: str, **extra):
    sc = im.Scenario.read(preset).with_overrides(
        {**SHORT, "control.speed_feedback": estimator, **extra}
    )
    return simulate(sc, record=True)


def assert_round_trip(res, rep, estimator: str) -> None:
    key = estimator.replace("-", "_")
    est = rep.signals[f"speed_est_{key}_rpm"]
    run = res.recording["speed_est_rpm"]  # the run's estimate at every period
    assert len(est) == len(run) == res.k_end + 1
    scale = np.max(np.abs(run))
    assert scale > 100.0  # the estimate moved: the comparison means something
    assert np.max(np.abs(est - run)) <= 1e-9 * scale
    logged = np.asarray(res.signals["speed_est_rpm"])  # and the logged column itself
    every = res.scenario.simulation.log_every
    assert np.max(np.abs(est[::every] - logged)) <= 1e-9 * scale
    R2 = rep.signals[f"R2_hat_{key}_ohm"]
    if rep.summary["estimators"][estimator]["R2_law"]:
        # the law replayed: R2_hat after its decision, what the estimator reads next period
        # and what the run logged
        assert np.max(np.abs(R2[:-1] - res.recording["R2_hat_ohm"][1:])) <= 1e-9 * np.max(R2)
        logged = np.asarray(res.signals["R2_hat_ohm"])
        assert np.max(np.abs(R2[::every] - logged)) <= 1e-9 * np.max(R2)
    else:
        assert np.max(np.abs(R2 - res.recording["R2_hat_after_ohm"])) <= 1e-9 * np.max(R2)
    assert rep.summary["estimators"][estimator]["status"] == "ok"


@pytest.mark.parametrize("preset", [DRIVES[0], pytest.param(DRIVES[1], marks=pytest.mark.slow)])
@pytest.mark.parametrize(
    "estimator",
    [ESTIMATORS[0]] + [pytest.param(e, marks=pytest.mark.slow) for e in ESTIMATORS[1:]],
)
def test_round_trip_every_estimator(preset, estimator, tmp_path):
    res = recorded(preset, estimator)
    res.save(tmp_path / "run", formats=["recording"])
    rep = replay(tmp_path / "run", estimators=estimator)
    assert_round_trip(res, rep, estimator)


@pytest.mark.slow
def test_round_trip_follows_the_compensators_R2_hat(tmp_path):
    """The R2 compensator writes R2_hat between estimator steps: the replay takes its writes."""
    res = recorded(
        "sensorless",
        "mras",
        **{
            "simulation.t_end_s": 1.0,
            "compensator.enabled": True,
            "compensator.t_on_s": 0.3,
            "estimator.R2_ohm": 1.0,
        },
    )
    assert np.unique(res.recording["R2_hat_ohm"]).size >= 3  # it wrote R2_hat, twice at least
    res.save(tmp_path / "run", formats=["recording"])
    rep = replay(tmp_path / "run", estimators="mras")
    assert rep.summary["estimators"]["mras"]["R2_law"]  # the paper's law, replayed
    assert "'table' law" in rep.summary["R2_law"]
    assert_round_trip(res, rep, "mras")
    # not replayed: R2_hat as the recorded controller wrote it
    off = replay(tmp_path / "run", estimators="mras", r2_law="off")
    assert not off.summary["estimators"]["mras"]["R2_law"]
    assert_round_trip(res, off, "mras")


def test_recording_does_not_change_the_run():
    sc = im.Scenario.read("sensorless").with_overrides(SHORT)
    plain = simulate(sc, record=False)
    rec = simulate(sc, record=True)
    assert plain.recording is None
    for name, v in plain.signals.items():
        assert np.asarray(v).tobytes() == np.asarray(rec.signals[name]).tobytes(), name
    # the recording's measured current and time are the log's at its rows
    every = sc.simulation.log_every
    for name in ("time_s", "i_alpha_meas_A", "i_beta_meas_A", "speed_est_rpm"):
        assert np.array_equal(rec.recording[name][::every], np.asarray(rec.signals[name]))
    assert np.allclose(rec.recording["speed_enc_rpm"][::every], rec.signals["speed_rpm"])


@pytest.mark.slow  # 1.5 s or more on 2 cores (3.1 s measured 2026-11-29)
def test_cli_run_format_recording_and_replay(tmp_path, capsys):
    run = tmp_path / "run"
    sets = ["--set", "simulation.t_end_s=0.2"]
    assert main(["run", "sensorless", *sets, "--format", "recording", "--out", str(run), "-q"]) == 0
    assert sorted(p.name for p in run.iterdir()) == [
        "recording.parquet",
        "recording.toml",
        "summary.json",
    ]
    rec = read_recording(run)
    assert rec.meta["recording"]["estimator"] == "mras"
    assert rec.meta["recording"]["sample_period_s"] == 1e-4
    assert rec.rows == 2001
    out = tmp_path / "rep"
    assert main(["replay", str(run), "--estimators", "mras,afo", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "replay.png",
        "report.html",
        "summary.json",
        "timeseries.parquet",
    ]
    t = pq.read_table(out / "timeseries.parquet")
    assert {"speed_est_mras_rpm", "speed_est_afo_rpm", "R2_hat_afo_ohm"} <= set(t.column_names)
    assert "replayed 2001 rows" in capsys.readouterr().err


# --- bad input --------------------------------------------------------------------------------


def good_columns(n: int = 50, Ts: float = 1e-4) -> dict:
    t = np.arange(n) * Ts
    return {
        "time_s": t,
        "i_alpha_meas_A": np.cos(2 * np.pi * 5 * t),
        "i_beta_meas_A": np.sin(2 * np.pi * 5 * t),
        "v_alpha_cmd_V": 10 * np.cos(2 * np.pi * 5 * t),
        "v_beta_cmd_V": 10 * np.sin(2 * np.pi * 5 * t),
    }


def write(path, cols) -> None:
    pq.write_table(pa.table(cols), str(path))


def bad(cols: dict, how: str) -> dict:
    cols = {k: v.copy() for k, v in cols.items()}
    t = cols["time_s"]
    if how == "missing":
        del cols["v_beta_cmd_V"]
    elif how == "duplicated":
        t[7] = t[6]
    elif how == "backwards":
        t[7] = t[5]
    elif how == "nan":
        cols["i_beta_meas_A"][12] = np.nan
    elif how == "inf":
        cols["v_alpha_cmd_V"][3] = np.inf
    elif how == "jitter":
        t[20:] += 0.05 * 1e-4
    elif how == "slow":
        cols["time_s"] = t * 2.0
    elif how == "no rows":
        cols = {k: v[:0] for k, v in cols.items()}
    return cols


#: how -> what the one line must name
BAD = {
    "missing": "column v_beta_cmd_V: missing",
    "duplicated": "column time_s row 7: time 0.0006 s repeats row 6's",
    "backwards": "column time_s row 7: time 0.0005 s goes back from row 6's",
    "nan": "column i_beta_meas_A row 12: is nan: every value must be finite",
    "inf": "column v_alpha_cmd_V row 3: is inf: every value must be finite",
    "jitter": "column time_s row 20: the sample period",
    "slow": "is longer than the controller's Ts",
    "no rows": "is empty",
    "empty file": "is empty",
}


@pytest.mark.parametrize("how", sorted(BAD))
def test_bad_recording_is_one_line_exit_2_nothing_written(how, tmp_path, capsys):
    path = tmp_path / "rec.parquet"
    if how == "empty file":
        path.write_bytes(b"")
    else:
        write(path, bad(good_columns(), how))
    out = tmp_path / "out"
    rc = main(["replay", str(path), "--scenario", "sensorless", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2
    assert err.count("\n") == 1 and err.startswith("imdrive: error: ")
    assert BAD[how] in err, err
    assert not out.exists()


def test_the_good_recording_passes_the_checks(tmp_path):
    path = tmp_path / "rec.parquet"
    write(path, good_columns())
    rec = read_recording(path)
    assert rec.rows == 50 and rec.period_s == pytest.approx(1e-4)
    assert set(REQUIRED) <= set(rec.columns)


def test_unknown_estimator_and_missing_scenario(tmp_path):
    path = tmp_path / "rec.parquet"
    write(path, good_columns())
    with pytest.raises(ConfigError, match="--estimators: no estimator 'nope'"):
        replay(path, "sensorless", "nope")
    with pytest.raises(ConfigError, match="--scenario: .* has no recording.toml"):
        replay(path)


def test_foreign_recording_replays_with_the_context_defaults(tmp_path):
    """Without the controller's context the replay runs (and says what it defaulted)."""
    sc = im.Scenario.read("sensorless").with_overrides(SHORT)
    res = simulate(sc, record=True)
    cols = {k: res.recording[k] for k in (*REQUIRED, "speed_enc_rpm")}
    path = tmp_path / "rec.parquet"
    write(path, cols)
    rep = replay(path, "sensorless", "mras")
    assert rep.summary["model"] == "the scenario's"
    assert "theta_e_rad" in rep.summary["context_defaulted"]
    # the MRAS's speed estimate needs neither the angle nor the references: the same
    key = "speed_est_mras_rpm"
    run = res.recording["speed_est_rpm"]
    assert np.max(np.abs(rep.signals[key] - run)) <= 1e-9 * np.max(np.abs(run))
    assert rep.summary["estimators"]["mras"]["speed_error_rpm"]["rms"] > 0.0


def test_csv_recording_replays_like_the_parquet(tmp_path):
    """The same recording as CSV (17 significant digits: exact float64) gives the same."""
    sc = im.Scenario.read("sensorless").with_overrides(SHORT)
    res = simulate(sc, record=True)
    res.save(tmp_path / "run", formats=["recording"])
    lines = [",".join(res.recording)]
    rows = np.column_stack(list(res.recording.values()))
    lines += [",".join(f"{x:.17g}" for x in row) for row in rows]
    csv = tmp_path / "rec.csv"
    csv.write_text("\n".join(lines) + "\n")
    a = replay(csv, "sensorless", "mras").signals["speed_est_mras_rpm"]
    b = replay(tmp_path / "run", estimators="mras").signals["speed_est_mras_rpm"]
    assert np.array_equal(a, b)
