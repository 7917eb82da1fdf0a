"""Foreign recordings (imdrive.run.recording_map, recording_read, decimate, replay_inputs).

The same recording written with other column names, mA, ms, rad/s, phase-to-phase voltages
and another phase order, read through a mapping file, replays to 1e-9 relative of the
recording's own; MAT files too. A recording at 4 x the controller rate, decimated, gives the
estimates of the one at the controller rate within 0.1 rpm. Bad input: one line, exit 2,
nothing written.
"""

from __future__ import annotations

import math

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import scipy.io

import imdrive as im
from imdrive.cli import main
from imdrive.errors import ConfigError
from imdrive.run.decimate import Decimator
from imdrive.run.recording import REQUIRED, read_recording
from imdrive.run.recording_map import parse_map, phase_to_neutral
from imdrive.run.replay import replay
from imdrive.run.simulate import simulate

SHORT = {
    "simulation.t_end_s": 0.3,
    "control.speed_ref_rpm": {"initial": 0, "changes": [{"at": 0.05, "to": 600, "over": 0.2}]},
}
SQ3 = math.sqrt(3.0)

#: the context columns under other names (mapped through [columns])
CONTEXT = {
    "theta_e_rad": "angle",
    "w_e_rad_s": "we",
    "id_ref_A": "idref",
    "iq_ref_A": "iqref",
    "w_ref_rad_s": "wref",
    "hold_R1_flag": "hold",
    "restart_flag": "restart",
    "i_inj_A": "iinj",
    "R1_hat_ohm": "R1",
    "R2_hat_ohm": "R2",
    "M_hat_H": "M",
    "R1_hat_after_ohm": "R1a",
    "R2_hat_after_ohm": "R2a",
    "t_hold_s": "thold",
    "v_use_pu": "vuse",
    "k_flux_pu": "kflux",
    "w_sl_rad_s": "wsl",
    "iq_meas_A": "iq",
    "L_inc_hat_H": "Linc",
    "w_fb_rad_s": "wfb",
}

MAP_TOML = """
[time]
column = "t_ms"
unit = "ms"

[current]
columns = ["Ia_mA", "Ic_mA", "Ib_mA"]
phase_order = "acb"
unit = "mA"

[voltage]
columns = ["Vac", "Vcb", "Vba"]
phase_order = "acb"
kind = "measured-phase-to-phase"

[speed]
column = "w_mech"
unit = "rad/s"

[columns]
""" + "\n".join(f'{k} = "{v}"' for k, v in CONTEXT.items())


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A short closed-loop run's recording (mras), saved."""
    folder = tmp_path_factory.mktemp("run")
    sc = im.Scenario.read("sensorless").with_overrides(SHORT)
    res = simulate(sc, record=True)
    res.save(folder / "run", formats=["recording"])
    return res, folder / "run"


def foreign_columns(r: dict) -> dict:
    """The recording as a foreign log: phases in the order a, c, b, mA, ms, line voltages
    (acb order: the file's 'Vac' is v_a - v_c), the encoder in rad/s."""
    ia, ib, ic = r["i_a_meas_A"], r["i_b_meas_A"], r["i_c_meas_A"]
    va = r["v_alpha_cmd_V"]
    vb = -0.5 * va + 0.5 * SQ3 * r["v_beta_cmd_V"]
    vc = -0.5 * va - 0.5 * SQ3 * r["v_beta_cmd_V"]
    cols = {
        "t_ms": r["time_s"] * 1e3,
        "Ia_mA": ia * 1e3,
        "Ic_mA": ic * 1e3,
        "Ib_mA": ib * 1e3,
        "Vac": va - vc,
        "Vcb": vc - vb,
        "Vba": vb - va,
        "w_mech": r["speed_enc_rpm"] * math.pi / 30.0,
    }
    return cols | {v: r[k] for k, v in CONTEXT.items()}


def write_csv(path, cols: dict) -> None:
    lines = [",".join(cols)]
    rows = np.column_stack(list(cols.values()))
    lines += [",".join(f"{x:.17g}" for x in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")


def rel_err(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


ESTIMATORS = ("mras", "afo")


def assert_same(rep, ref, tol: float = 1e-9) -> None:
    for name in ESTIMATORS:
        key = f"speed_est_{name}_rpm"
        assert np.max(np.abs(ref.signals[key])) > 100.0  # the estimate moved
        assert rel_err(rep.signals[key], ref.signals[key]) <= tol, name
        r2 = f"R2_hat_{name}_ohm"
        assert rel_err(rep.signals[r2], ref.signals[r2]) <= tol, name
    assert rel_err(rep.signals["speed_enc_rpm"], ref.signals["speed_enc_rpm"]) <= tol


def test_phase_to_neutral_is_the_zero_sum_solution():
    rng = np.random.default_rng(1)
    va, vb = rng.normal(size=5), rng.normal(size=5)
    vc = -va - vb
    a, b, c = phase_to_neutral(va - vb, vb - vc, vc - va)
    assert np.allclose([a, b, c], [va, vb, vc], atol=1e-14)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2.5-2.8 s measured 2026-11-29)
def test_csv_with_other_names_and_units_through_a_map(run, tmp_path):
    res, folder = run
    ref = replay(folder, estimators=ESTIMATORS)
    csv = tmp_path / "scope.csv"
    write_csv(csv, foreign_columns(res.recording))
    mp = tmp_path / "map.toml"
    mp.write_text(MAP_TOML)
    out = tmp_path / "rep"
    rc = main(
        ["replay", str(csv), "--map", str(mp), "--scenario", "sensorless", "--estimators",
         "mras,afo", "--out", str(out), "-q"]
    )  # fmt: skip
    assert rc == 0
    rep = replay(csv, "sensorless", ESTIMATORS, mapping=mp)
    assert_same(rep, ref)
    assert rep.summary["context_defaulted"] == []
    assert rep.summary["mapping"]["voltage"]["kind"] == "measured-phase-to-phase"
    t = pq.read_table(out / "timeseries.parquet")
    assert rel_err(t["speed_est_afo_rpm"].to_numpy(), ref.signals["speed_est_afo_rpm"]) <= 1e-9


@pytest.mark.slow
def test_the_r2_law_replays_the_same_through_a_map(tmp_path):
    """An R2-tracking drive's recording as the foreign CSV: each estimator's law gives the
    R2_hat of the recording's own replay to 1e-9."""
    sc = im.Scenario.read("injection-robust").with_overrides({"simulation.t_end_s": 6.0})
    res = simulate(sc, record=True)
    res.save(tmp_path / "run", formats=["recording"])
    ref = replay(tmp_path / "run", estimators=ESTIMATORS)
    csv = tmp_path / "scope.csv"
    write_csv(csv, foreign_columns(res.recording))
    mp = tmp_path / "map.toml"
    mp.write_text(MAP_TOML)
    rep = replay(csv, sc, ESTIMATORS, mapping=mp)
    for name in ESTIMATORS:
        assert rep.summary["estimators"][name]["R2_law"]
        R2 = rep.signals[f"R2_hat_{name}_ohm"]
        assert R2[-1] < 0.9 * R2[0]  # the law moved it (from 1.2 R2)
    assert_same(rep, ref)


@pytest.mark.parametrize("layout", ["variables", "struct"])
def test_mat_file_replays_the_same(run, tmp_path, layout):
    res, folder = run
    ref = replay(folder, estimators=ESTIMATORS)
    cols = foreign_columns(res.recording)
    mat = tmp_path / "log.mat"
    scipy.io.savemat(mat, cols if layout == "variables" else {"log": cols})
    rep = replay(mat, "sensorless", ESTIMATORS, mapping=parse_map(_toml(MAP_TOML)))
    assert_same(rep, ref)


def _toml(text: str) -> dict:
    import tomllib

    return tomllib.loads(text)


def test_mat_v73_is_refused_with_the_reason(tmp_path, capsys):
    """A v7.3 MAT file is HDF5: refused naming h5py (not installed here)."""
    pytest.importorskip("scipy")
    try:
        import h5py  # noqa: F401

        pytest.skip("h5py is installed: v7.3 files are read")
    except ImportError:
        pass
    mat = tmp_path / "log.mat"
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5"
    mat.write_bytes(header.ljust(116, b" ") + b"\0" * 8 + b"\x00\x02" + b"IM" + b"\0" * 512)
    out = tmp_path / "out"
    rc = main(["replay", str(mat), "--scenario", "sensorless", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1
    assert "MAT v7.3 file (HDF5)" in err and "h5py" in err and "-v7" in err
    assert not out.exists()


def one_line_exit_2(capsys, args, out) -> str:
    rc = main([*args, "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 2, err
    assert err.count("\n") == 1 and err.startswith("imdrive: error: ")
    assert not out.exists()
    return err


def test_a_map_naming_a_column_twice_is_bad_input(run, tmp_path, capsys):
    res, _ = run
    csv = tmp_path / "scope.csv"
    write_csv(csv, foreign_columns(res.recording))
    mp = tmp_path / "map.toml"
    mp.write_text(MAP_TOML.replace('column = "w_mech"', 'column = "Ia_mA"'))
    err = one_line_exit_2(
        capsys, ["replay", str(csv), "--map", str(mp), "--scenario", "sensorless"], tmp_path / "o"
    )
    assert "speed.column: names the column 'Ia_mA' that current.columns names too" in err


def test_a_mapped_column_missing_from_the_file(run, tmp_path, capsys):
    res, _ = run
    csv = tmp_path / "scope.csv"
    write_csv(csv, foreign_columns(res.recording))
    mp = tmp_path / "map.toml"
    mp.write_text(MAP_TOML.replace('"Vba"', '"Vbx"'))
    err = one_line_exit_2(
        capsys, ["replay", str(csv), "--map", str(mp), "--scenario", "sensorless"], tmp_path / "o"
    )
    assert "column Vbx: missing: the mapping" in err


def test_currents_1000_times_rated_are_a_unit_error(run, tmp_path, capsys):
    """mA read as A: the current is 1000 times what it is; refused naming the column."""
    res, _ = run
    csv = tmp_path / "scope.csv"
    write_csv(csv, foreign_columns(res.recording))
    mp = tmp_path / "map.toml"
    mp.write_text(MAP_TOML.replace('unit = "mA"', 'unit = "A"'))
    err = one_line_exit_2(
        capsys,
        ["replay", str(csv), "--map", str(mp), "--scenario", "sensorless", "--estimators", "mras"],
        tmp_path / "o",
    )
    assert "column Ia_mA, Ic_mA, Ib_mA row " in err
    assert "times the machine's rated peak current" in err and "check the unit, A or mA" in err


def test_a_non_integer_rate_is_refused_and_the_file_period_accepted(run, tmp_path, capsys):
    res, _ = run
    cols = {k: res.recording[k] for k in REQUIRED}
    cols["time_s"] = cols["time_s"] / 2.5  # 2.5 x the controller's rate
    path = tmp_path / "rec.parquet"
    pq.write_table(pa.table(cols), str(path))
    err = one_line_exit_2(capsys, ["replay", str(path), "--scenario", "sensorless"], tmp_path / "o")
    assert "does not divide the controller's Ts" in err and "ratio 2.5" in err
    rep = replay(path, "sensorless", "mras", controller_period="file")
    assert rep.summary["period_replayed_s"] == pytest.approx(4e-5)
    assert rep.summary["decimation"] == 1


def test_the_decimator_in_chunks_is_the_decimator_in_one():
    rng = np.random.default_rng(0)
    n = 5003
    cols = {
        "time_s": np.arange(n) * 1e-5,
        "i_alpha_meas_A": rng.normal(size=n),
        "v_alpha_cmd_V": rng.normal(size=n),
    }
    whole = Decimator(4).push(cols)
    d = Decimator(4)
    parts = [d.push({k: v[i : i + 333] for k, v in cols.items()}) for i in range(0, n, 333)]
    got = {k: np.concatenate([p[k] for p in parts if p]) for k in cols}
    e = d.edge
    rows = np.arange(e, n // 4 - e + 1)  # every output row whose window is inside
    assert len(whole["time_s"]) == rows.size
    for k in cols:
        assert np.allclose(got[k], whole[k], rtol=0, atol=1e-13)
    assert np.array_equal(whole["time_s"], cols["time_s"][4 * rows])
    v = cols["v_alpha_cmd_V"]
    assert np.allclose(whole["v_alpha_cmd_V"], [v[4 * j : 4 * j + 4].mean() for j in rows])
    # the filter has no phase: a slow sine comes back at its own samples
    t = np.arange(n) * 1e-5
    x = np.sin(2 * np.pi * 50 * t)
    y = Decimator(4).push({"time_s": t, "i_alpha_meas_A": x})
    assert np.max(np.abs(y["i_alpha_meas_A"] - x[4 * rows])) < 1e-4


def test_a_4x_recording_decimated_gives_the_controller_rate_estimates(tmp_path):
    """A recording at 4 x the controller rate, decimated, within 0.1 rpm of one at its rate.

    How the two recordings are made: one drive, logged at two rates. The drive is simulated with
    its controller (and so its log) at Ts/4 = 25 us and recorded: that is the 4x recording. A
    logger at Ts = 100 us on the same drive would hold the current sampled at every 4th instant
    and, as the voltage of each period [t_k, t_k + Ts), the mean of the four commands applied
    over it: that is the controller-rate recording, made from the same samples without any
    filtering, from the decimator's first row on (it drops the first and last 12 periods, whose
    filter window would reach beyond the recording). Both are replayed with the drive's scenario
    at Ts; the 4x one goes through the decimator (the anti-aliasing FIR on the currents and the
    encoder, the period mean on the voltages). The speed estimates of mras, afo and ekf must
    agree within 0.1 rpm over the whole run while they move by hundreds of rpm; a filter with a
    phase lag, or a voltage taken at the wrong instant, breaks it (the estimators compare
    current with voltage).
    """
    sc = im.Scenario.read("sensorless").with_overrides(SHORT)
    fast = simulate(sc.with_overrides({"simulation.Ts_s": 2.5e-5}), record=True).recording
    keep = [*REQUIRED, "speed_enc_rpm"]
    f4 = {k: fast[k] for k in keep}
    e = Decimator(4).edge  # the decimator's first row is the fast row 4 e
    n = len(f4["time_s"]) // 4 - e
    f1 = {k: f4[k][4 * e : 4 * (e + n) : 4] for k in keep}
    for k in ("v_alpha_cmd_V", "v_beta_cmd_V"):
        f1[k] = f4[k][4 * e : 4 * (e + n)].reshape(n, 4).mean(axis=1)
    p4, p1 = tmp_path / "x4.parquet", tmp_path / "x1.parquet"
    pq.write_table(pa.table(f4), str(p4))
    pq.write_table(pa.table(f1), str(p1))
    names = ("mras", "afo", "ekf")
    r4 = replay(p4, "sensorless", names)
    r1 = replay(p1, "sensorless", names)
    assert r4.summary["decimation"] == 4 and r1.summary["decimation"] == 1
    rows = slice(0, r4.summary["rows_replayed"])  # the last e rows are not decimated
    assert np.array_equal(r4.signals["time_s"], r1.signals["time_s"][rows])
    for name in names:
        key = f"speed_est_{name}_rpm"
        assert np.ptp(r1.signals[key]) > 300.0
        diff = np.max(np.abs(r4.signals[key] - r1.signals[key][rows]))
        assert diff < 0.1, (name, diff)


def test_read_recording_with_a_map_gives_the_recordings_columns(run, tmp_path):
    res, _ = run
    csv = tmp_path / "scope.csv"
    write_csv(csv, foreign_columns(res.recording))
    mp = tmp_path / "map.toml"
    mp.write_text(MAP_TOML)
    rec = read_recording(csv, mp)
    for k in ("i_alpha_meas_A", "i_beta_meas_A", "v_alpha_cmd_V", "v_beta_cmd_V"):
        assert rel_err(rec.columns[k], res.recording[k]) < 1e-12, k
    with pytest.raises(ConfigError, match="voltage.kind: must be one of"):
        parse_map({"time": {"column": "t"}, "current": {"columns": ["a", "b"]},
                   "voltage": {"columns": ["x", "y"], "kind": "ab"}})  # fmt: skip


@pytest.mark.slow  # 1.5 s or more on 2 cores (2.8-3.6 s measured 2026-11-29)
def test_compare_takes_replay_folders_and_replay_writes_its_report(run, tmp_path):
    """A replay folder holds replay.png and report.html; imdrive compare takes it with a
    line per estimator, its metrics the replay's errors."""
    from imdrive.run.compare import compare

    _, folder = run
    a = tmp_path / "rep-a"
    replay(folder, estimators=["mras", "afo"], out=a)
    html = (a / "report.html").read_text()
    assert "speed estimate - encoder" in html and "afo" in html
    assert (a / "replay.png").stat().st_size > 10_000
    out = tmp_path / "cmp"
    c = compare([a])
    assert [r.label for r in c.runs] == ["rep-a: mras", "rep-a: afo"]
    assert {"speed", "speed estimate error", "rotor resistance estimate"} <= {
        q for q, _ in c.panels
    }
    m = c.metrics
    rep = replay(folder, estimators=["mras", "afo"])
    assert m.loc["speed_error_rms_rpm", "rep-a: afo"] == pytest.approx(
        rep.summary["estimators"]["afo"]["speed_error_rpm"]["rms"]
    )
    assert main(["compare", str(a), "--out", str(out), "-q"]) == 0
    assert (out / "report.html").is_file() and (out / "metrics.csv").is_file()
