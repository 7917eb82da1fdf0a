"""The R2 law replayed (imdrive.run.replay with the scenario's compensator, kernels/r2_tracking.py).

The round trip: a closed-loop run of an R2-tracking drive, replayed with its own estimator
and law, gives back the run's R2_hat (what its estimator read each next period, and its log)
and speed estimate to 1e-9 relative: every registered estimator with the Kalman law and the
injection, the realistic drive (saturating model, dead time, sensors), a user's plug-in law.
Replayed with other estimators, the law tracks R2 on each one's flux error. A scenario whose
injection is not the drive's says so; "--r2-law on" where no law can run is refused.
"""

from __future__ import annotations

import numpy as np
import pytest

import imdrive as im
from imdrive.cli import main
from imdrive.errors import ConfigError, ConfigWarning
from imdrive.run.replay import replay
from imdrive.run.simulate import simulate

ESTIMATORS = ("mras", "smo-mras", "reactive-mras", "afo", "ekf")
#: the own law of tests/drive/test_own_r2_law.py (a relaxation on the window's measurement)
MODULE = str(__import__("pathlib").Path(__file__).parents[1] / "data" / "own_r2_law.py")
#: the recommended drive on the MRAS, whose recordings these tests replay (the preset runs
#: the adaptive observer since 2026-11-30; its round trip: the test over every estimator)
MRAS = 'control.speed_feedback="mras"'

LAW = [f'plugins.modules=["{MODULE}"]', 'compensator.step_law="relax"']


def recorded(tmp_path, preset: str, *overrides: str, plugins: bool = False):
    sc = im.Scenario.read(preset, list(overrides), allow_plugins=plugins)
    res = simulate(sc, record=True)
    res.save(tmp_path / "run", formats=["recording"])
    return res


def assert_law_round_trip(res, rep, estimator: str) -> None:
    key = estimator.replace("-", "_")
    e = rep.summary["estimators"][estimator]
    assert e["R2_law"] and e["status"] == "ok"
    assert e["injection_difference_A"] == 0.0  # the law's injection is the recorded one
    R2 = rep.signals[f"R2_hat_{key}_ohm"]
    run = res.recording["R2_hat_ohm"]  # what the run's estimator read, one period later
    assert np.ptp(run) > 0.1 * np.max(run)  # the law moved R2_hat: the comparison means much
    assert np.max(np.abs(R2[:-1] - run[1:])) <= 1e-9 * np.max(R2)
    every = res.scenario.simulation.log_every
    assert np.max(np.abs(R2[::every] - np.asarray(res.signals["R2_hat_ohm"]))) <= 1e-9 * R2.max()
    w = rep.signals[f"speed_est_{key}_rpm"]
    assert np.max(np.abs(w - res.recording["speed_est_rpm"])) <= 1e-9 * np.max(np.abs(w))
    assert e["R2_hat_ohm"]["tail_mean"] == pytest.approx(res.scenario.machine.R2_ohm, rel=0.01)


@pytest.mark.parametrize(
    "estimator",
    [ESTIMATORS[0]] + [pytest.param(e, marks=pytest.mark.slow) for e in ESTIMATORS[1:]],
)
def test_the_law_round_trips_with_every_estimator(estimator, tmp_path):
    """injection-robust (the Kalman law, the injection, R2_hat(0) = 1.2 R2)."""
    res = recorded(tmp_path, "injection-robust", f'control.speed_feedback="{estimator}"')
    rep = replay(tmp_path / "run", estimators=estimator)
    assert "'kalman' law" in rep.summary["R2_law"] and "injection" in rep.summary["R2_law"]
    assert_law_round_trip(res, rep, estimator)


@pytest.mark.slow
@pytest.mark.parametrize("estimator", ["mras", "afo"])
def test_the_law_round_trips_on_the_realistic_drive(estimator, tmp_path):
    """The commissioned realistic drive: its saturating model's incremental inductance, which
    the detection reads, is the controller's (recorded), as are its R1_hat writes."""
    res = recorded(tmp_path, "injection-fig5-realistic", f'control.speed_feedback="{estimator}"')
    rep = replay(tmp_path / "run", estimators=estimator)
    assert_law_round_trip(res, rep, estimator)


@pytest.mark.slow
@pytest.mark.parametrize("machine", ["aalto-2.2kw", "krause-50hp"])
def test_a_plug_in_law_replays_and_tracks_on_other_estimators(machine, tmp_path):
    """A user's law (tests/data/own_r2_law.py) replays through the registry: its own run back
    exactly, and on the other estimators' flux errors R2 within 1 %. Their estimates differ
    from the drive's: the law's gate reads the drive's recorded speed feedback (on its own
    estimate the EKF's gate held R2_hat 20 % off for the whole replay on the Aalto machine)."""
    res = recorded(
        tmp_path, "injection-robust", *LAW, f'machine.preset="{machine}"', MRAS, plugins=True
    )
    rep = replay(tmp_path / "run", estimators="mras,afo,ekf")
    assert "'relax' law" in rep.summary["R2_law"]
    assert_law_round_trip(res, rep, "mras")
    R2 = res.scenario.machine.R2_ohm
    for name in ("afo", "ekf"):
        e = rep.summary["estimators"][name]
        assert e["R2_law"] and e["status"] == "ok"
        assert e["R2_hat_end_ohm"] == pytest.approx(R2, rel=0.01), name
        assert e["R2_hat_ohm"]["max"] > 1.15 * R2  # it started from the run's 1.2 R2


@pytest.mark.slow
def test_r2_law_off_auto_without_excitation_and_on_refused(tmp_path, capsys):
    res = recorded(tmp_path, "injection-robust", "simulation.t_end_s=6.0", MRAS)
    run = tmp_path / "run"
    off = replay(run, r2_law="off")
    e = off.summary["estimators"]["mras"]
    assert not e["R2_law"] and "--r2-law off" in off.summary["R2_law"]
    # R2_hat as the recorded controller wrote it: the run's, right after each estimator step
    R2 = off.signals["R2_hat_mras_ohm"]
    assert np.ptp(res.recording["R2_hat_after_ohm"]) > 0.0  # the run's law wrote it
    assert np.max(np.abs(R2 - res.recording["R2_hat_after_ohm"])) <= 1e-9 * np.max(R2)
    # a recording without its excitation (a CSV without i_inj_A): auto does not run the
    # law, and says why
    csv = tmp_path / "noinj.csv"
    keep = [k for k in res.recording if k not in ("i_inj_A",)]
    rows = np.column_stack([res.recording[k] for k in keep])
    csv.write_text(
        ",".join(keep) + "\n" + "\n".join(",".join(f"{x:.17g}" for x in r) for r in rows) + "\n"
    )
    auto = replay(csv, res.scenario)
    assert not auto.summary["estimators"]["mras"]["R2_law"]
    assert "i_inj_A" in auto.summary["R2_law"]
    with pytest.raises(ConfigError, match="--r2-law.*i_inj_A"):
        replay(csv, res.scenario, r2_law="on")
    # no law in the scenario: "on" refused by the CLI, one line, exit 2, nothing written
    out = tmp_path / "rep"
    rc = main(["replay", str(run), "--scenario", "sensorless", "--r2-law", "on", "--out", str(out)])
    assert rc == 2 and not out.exists()
    err = capsys.readouterr().err
    assert "--r2-law" in err and "compensator.enabled" in err and "Traceback" not in err


@pytest.mark.slow
def test_an_injection_not_the_drives_is_said(tmp_path, capsys):
    """Replayed with another injection frequency than the drive's, the law demodulates out of
    step: the summary and the console say so."""
    res = recorded(tmp_path, "injection-robust", "simulation.t_end_s=6.0", MRAS)
    f = res.scenario.injection.frequency_pu
    other = res.scenario.with_overrides({"injection.frequency_pu": 1.5 * f})
    with pytest.warns(ConfigWarning, match="injection differs"):
        rep = replay(tmp_path / "run", other)
    assert rep.summary["warnings"] and "R2_warning" in rep.summary["estimators"]["mras"]
    toml = tmp_path / "other.toml"
    toml.write_text(other.to_toml())
    rc = main(
        ["replay", str(tmp_path / "run"), "--scenario", str(toml), "--out", str(tmp_path / "o")]
    )
    assert rc == 0
    assert "imdrive: warning:" in capsys.readouterr().err


@pytest.mark.slow
def test_a_plug_in_recording_replays_only_with_allow_plugins(tmp_path):
    """The recording of a run with a plug-in law names the module relative to its folder;
    ``imdrive replay`` from another folder imports it only with ``--allow-plugins`` (a fresh
    process: in this one the module is imported already, which runs nothing and passes)."""
    import subprocess
    import sys

    recorded(tmp_path, "injection-robust", *LAW, "simulation.t_end_s=5.0", plugins=True)
    elsewhere = tmp_path / "a" / "b"
    elsewhere.mkdir(parents=True)

    def cli(*extra):
        cmd = [sys.executable, "-m", "imdrive", "replay", str(tmp_path / "run"), "-q"]
        return subprocess.run(
            [*cmd, "--out", str(tmp_path / "rep"), *extra],
            cwd=elsewhere, capture_output=True, text=True, timeout=600,
        )  # fmt: skip

    refused = cli()
    assert refused.returncode == 2 and "--allow-plugins" in refused.stderr
    assert "own_r2_law.py" in refused.stderr and "Traceback" not in refused.stderr
    assert not (tmp_path / "rep").exists()
    ok = cli("--allow-plugins")
    assert ok.returncode == 0, ok.stderr
    assert (tmp_path / "rep" / "summary.json").exists()
