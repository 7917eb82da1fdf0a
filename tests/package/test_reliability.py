"""Reliability: each class of defect in storing, naming and running, as a test.

1. damaged sweep stores resume; writes are durable; one writer per store;
2. a run whose derived parameters overflow is refused (imdrive run) or recorded as failed
   (sweeps, batches) while the others go on;
3. hostile names cannot write outside the output root;
4. documented exit codes, one-line errors for environment failures (full disk, read-only
   folder, memory, internal errors), what was written looks incomplete;
5. a result folder is replaced as a whole, leftovers are cleaned;
6. physical and consistency rules for every field; a property-based test of the loader;
7. the size guard on sweeps;
8. strict JSON in summary.json, a byte-order mark, ``--out ''``, an unknown base, the manifest
   says complete only after the figures.
"""

from __future__ import annotations

import errno
import json
import math
import os
import shutil
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from imdrive import cli
from imdrive._io import FolderLock, atomic_write_text
from imdrive.cli import main
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError, EnvironmentFailure
from imdrive.run.batch import S_FAILED, simulate_batch
from imdrive.run.build import build_arrays
from imdrive.sweep import load_sweep, parse_sweep, run_sweep
from imdrive.sweep.store import Store

# 3 x 2 = 6 very short runs, chunks of 2
TINY = """
name = "tiny"
base = "sensorless"
chunk_size = 2
window_s = 0.01

[set]
simulation.t_end_s = 0.03
control.speed_ref_rpm = 300

[axes]
R2_ratio = [0.8, 1.0, 1.2]
speed_rpm = [300, 600]
"""

# the second value of J makes the speed PI gain (J a_s^2 / k_t) overflow to infinity
OVERFLOW = """
name = "overflow"
base = "sensorless"
chunk_size = 2
window_s = 0.01

[set]
simulation.t_end_s = 0.03
control.speed_bandwidth_Hz = 1e150

[axes]
"machine.J_kgm2" = [0.069, 1e150, 0.1]
"""


def _fail_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.fixture(scope="module")
def tiny_full(tmp_path_factory):
    out = tmp_path_factory.mktemp("tiny") / "store"
    df = run_sweep(parse_sweep(TINY), out, progress=False, figures=False)
    return out, df


# ------------------------------------------------------------------------------------------
# 1. damaged stores, durability, lock


def test_damaged_chunks_are_recomputed_and_the_table_is_the_same(tiny_full, tmp_path):
    full_out, full = tiny_full
    out = tmp_path / "store"
    shutil.copytree(full_out, out)
    (out / "runs.parquet").unlink()
    man = json.loads((out / "manifest.json").read_text())
    man["complete"] = False
    (out / "manifest.json").write_text(json.dumps(man))
    chunks = Store(out).chunks
    data = (chunks / "chunk-000000.parquet").read_bytes()
    (chunks / "chunk-000000.parquet").write_bytes(data[: len(data) // 2])  # truncated
    (chunks / "chunk-000001.parquet").write_bytes(b"")  # empty
    # foreign: a readable Parquet file with the right columns but other runs
    pd.read_parquet(full_out / "chunks" / "chunk-000000.parquet").to_parquet(
        chunks / "chunk-000002.parquet", index=False
    )
    (chunks / "chunk-000007.parquet").write_bytes(data)  # beyond the sweep's chunks
    notes: list[str] = []
    df = run_sweep(
        parse_sweep(TINY), out, resume=True, progress=False, figures=False, notice=notes.append
    )
    pd.testing.assert_frame_equal(df, full)
    assert len(notes) == 4, notes
    assert any("unreadable" in n for n in notes) and any("exactly" in n for n in notes)
    assert sorted(p.name for p in chunks.iterdir()) == [f"chunk-00000{j}.parquet" for j in range(3)]
    assert json.loads((out / "manifest.json").read_text())["complete"] is True
    # a second resume finds nothing to repair
    notes.clear()
    again = run_sweep(
        parse_sweep(TINY), out, resume=True, progress=False, figures=False, notice=notes.append
    )
    assert notes == []
    pd.testing.assert_frame_equal(again, full)


def test_chunk_with_foreign_columns_is_recomputed(tiny_full, tmp_path):
    full_out, full = tiny_full
    out = tmp_path / "store"
    shutil.copytree(full_out, out)
    pd.DataFrame({"run": [0, 1], "x": [1.0, 2.0]}).to_parquet(
        out / "chunks" / "chunk-000000.parquet", index=False
    )
    notes: list[str] = []
    df = run_sweep(
        parse_sweep(TINY), out, resume=True, progress=False, figures=False, notice=notes.append
    )
    assert len(notes) == 1 and "foreign" in notes[0]
    pd.testing.assert_frame_equal(df, full)


def test_writes_are_fsynced_before_and_after_the_rename(tmp_path, monkeypatch):
    calls = []
    real = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (calls.append(fd), real(fd)))
    atomic_write_text(tmp_path / "a.json", "{}")
    assert len(calls) == 2  # the file, then its folder


def test_two_writers_cannot_share_a_store(tmp_path):
    out = tmp_path / "store"
    out.mkdir()
    with FolderLock(out), pytest.raises(EnvironmentFailure, match="in use"):
        run_sweep(parse_sweep(TINY), out, resume=True, progress=False, figures=False)
    assert not (out / "chunks" / "chunk-000000.parquet").exists()


# ------------------------------------------------------------------------------------------
# 2. derived quantities


def test_overflowing_derived_gain_is_bad_input_for_a_run(tmp_path, capsys):
    out = tmp_path / "run"
    rc = main(
        [
            "run",
            "sensorless",
            "--out",
            str(out),
            "-q",
            "--set",
            "machine.J_kgm2=1e150",
            "--set",
            "control.speed_bandwidth_Hz=1e150",
        ]
    )
    assert rc == cli.EXIT_BAD_INPUT
    line = _fail_line(capsys)
    assert "control.speed_bandwidth_Hz" in line and "speed_ki" in line
    assert not out.exists()


def test_sweep_with_an_overflowing_run_finishes_the_others(tmp_path):
    sweep = parse_sweep(OVERFLOW)
    assert sweep.validation["n_failing"] == 1  # known before anything runs
    df = run_sweep(sweep, tmp_path / "store", progress=False, figures=False)
    assert list(df["status"] == S_FAILED) == [False, True, False]
    assert "speed_bandwidth_Hz" in df["error"][1] and df["error"][0] == ""
    assert np.isnan(df["speed_error_rpm"][1]) and np.isfinite(df["speed_error_rpm"][0])
    assert not df["diverged"][1]


def test_batch_records_a_failed_build(tmp_path):
    good = Scenario.read("sensorless", ["simulation.t_end_s=0.02"])
    bad = Scenario.read(
        "sensorless",
        ["simulation.t_end_s=0.02", "machine.J_kgm2=1e150", "control.speed_bandwidth_Hz=1e150"],
    )
    with pytest.raises(ConfigError):
        simulate_batch([good, bad])
    res = simulate_batch([good, bad, good], errors="record", window_s=0.01)
    assert list(res.metrics["status"]) == [0, S_FAILED, 0]
    assert res.metrics["speed_error_rpm"][0] == res.metrics["speed_error_rpm"][2]


# ------------------------------------------------------------------------------------------
# 3. names


HOSTILE = ["../../evil", "/tmp/evil", "", "a" * 300, ".hidden", "a/b", "..", "x\x00y"]


@pytest.mark.parametrize("name", HOSTILE, ids=range(len(HOSTILE)))
def test_hostile_scenario_name_is_refused(tmp_path, monkeypatch, capsys, name):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    rc = main(
        [
            "run",
            "sensorless",
            "-q",
            "--set",
            f"name={json.dumps(name)}",
            "--set",
            "simulation.t_end_s=0.01",
        ]
    )
    assert rc == cli.EXIT_BAD_INPUT
    assert _fail_line(capsys).startswith("imdrive: error: name:")
    assert list(tmp_path.rglob("*")) == [work]


@pytest.mark.parametrize("name", HOSTILE[:5], ids=range(5))
def test_hostile_sweep_name_is_refused(tmp_path, name):
    with pytest.raises(ConfigError) as exc:
        parse_sweep(TINY.replace('name = "tiny"', f"name = {json.dumps(name)}"))
    assert exc.value.field == "name"


def test_sweep_file_name_is_slugified_for_the_default_name(tmp_path):
    f = tmp_path / "my sweep (1).toml"
    f.write_text(TINY.replace('name = "tiny"\n', ""))
    assert load_sweep(str(f)).name == "my-sweep--1-"


# ------------------------------------------------------------------------------------------
# 4. exit codes, environment failures


def test_exit_codes_are_documented():
    assert (cli.EXIT_OK, cli.EXIT_DIVERGED, cli.EXIT_BAD_INPUT) == (0, 1, 2)
    assert (cli.EXIT_LOST_CONTROL, cli.EXIT_ENVIRONMENT, cli.EXIT_INTERNAL) == (3, 4, 5)
    readme = (Path(__file__).parents[2] / "README.md").read_text()
    for code in range(6):
        assert f"| {code} |" in readme, code
        assert f"\n{code} (``EXIT_" in cli.__doc__


def _enospc(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device", "timeseries.csv")


def test_full_disk_gives_one_line_and_keeps_the_old_result(tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    args = [
        "run",
        "sensorless",
        "--out",
        str(out),
        "-q",
        "--set",
        "simulation.t_end_s=0.01",
        "--set",
        "output.figures=false",
    ]
    assert main(args) == cli.EXIT_OK
    before = (out / "summary.json").read_bytes()
    monkeypatch.setattr("imdrive.run.result.SimulationResult.to_csv", _enospc)
    assert main(args) == cli.EXIT_ENVIRONMENT
    line = _fail_line(capsys)
    assert "No space left on device" in line and "ENOSPC" in line
    assert (out / "summary.json").read_bytes() == before  # the earlier result, untouched
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".partial")]


def test_full_disk_on_a_fresh_folder_leaves_nothing_complete(tmp_path, monkeypatch, capsys):
    out = tmp_path / "run"
    monkeypatch.setattr("imdrive.run.result.SimulationResult.to_csv", _enospc)
    rc = main(["run", "sensorless", "--out", str(out), "-q", "--set", "simulation.t_end_s=0.01"])
    assert rc == cli.EXIT_ENVIRONMENT
    _fail_line(capsys)
    assert not (out / "summary.json").exists()


def test_full_disk_during_a_sweep_keeps_what_was_written(tmp_path, monkeypatch, capsys):
    f = tmp_path / "tiny.toml"
    f.write_text(TINY)
    out = tmp_path / "store"
    real = Store.write_chunk
    calls = []

    def write_chunk(self, j, df):
        calls.append(j)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device", str(self.chunk_path(j)))
        real(self, j, df)

    monkeypatch.setattr(Store, "write_chunk", write_chunk)
    rc = main(["sweep", str(f), "--out", str(out), "-q", "--no-figures"])
    assert rc == cli.EXIT_ENVIRONMENT
    assert "No space left on device" in _fail_line(capsys)
    man = json.loads((out / "manifest.json").read_text())
    assert man["complete"] is False and man["completed_chunks"] == [0]
    monkeypatch.setattr(Store, "write_chunk", real)
    assert main(["sweep", str(f), "--out", str(out), "-q", "--no-figures", "--resume"]) == 0


@pytest.mark.skipif(os.geteuid() == 0, reason="root ignores folder permissions")
def test_read_only_out_is_an_environment_failure(tmp_path, capsys):
    parent = tmp_path / "ro"
    parent.mkdir()
    parent.chmod(0o500)
    try:
        rc = main(
            [
                "run",
                "sensorless",
                "--out",
                str(parent / "run"),
                "-q",
                "--set",
                "simulation.t_end_s=0.01",
            ]
        )
    finally:
        parent.chmod(0o700)
    assert rc == cli.EXIT_ENVIRONMENT
    assert "Permission denied" in _fail_line(capsys)


def test_too_long_out_is_bad_input(tmp_path, capsys):
    rc = main(["run", "sensorless", "--out", str(tmp_path / ("x" * 300)), "-q"])
    assert rc == cli.EXIT_BAD_INPUT
    assert "--out" in _fail_line(capsys)


@pytest.mark.parametrize(
    ("exc", "code", "text"),
    [
        (MemoryError(), cli.EXIT_ENVIRONMENT, "out of memory"),
        (EnvironmentFailure("the dask cluster failed"), cli.EXIT_ENVIRONMENT, "dask"),
        (RuntimeError("boom"), cli.EXIT_INTERNAL, "internal error (RuntimeError: boom)"),
    ],
)
def test_unexpected_failures_are_one_line(tmp_path, monkeypatch, capsys, exc, code, text):
    def boom(*a, **k):
        raise exc

    import sys

    monkeypatch.setattr(sys.modules["imdrive.run.simulate"], "simulate", boom)
    rc = main(["run", "sensorless", "--out", str(tmp_path / "r"), "-q"])
    assert rc == code
    assert text in _fail_line(capsys)


def test_dask_failures_are_recognised():
    from imdrive.sweep.run import _from_dask

    Killed = type("KilledWorker", (Exception,), {"__module__": "distributed.scheduler"})
    assert _from_dask(Killed("w")) and _from_dask(TimeoutError())
    assert not _from_dask(ValueError("x"))


# ------------------------------------------------------------------------------------------
# 5. result folders


def test_reused_out_is_replaced_as_a_whole(tmp_path, capsys):
    out = tmp_path / "run"
    base = ["run", "sensorless", "--out", str(out), "-q", "--set", "simulation.t_end_s=0.01"]
    assert main([*base, "--set", "output.figures=false"]) == 0
    (out / "stale.png").write_bytes(b"old")
    # a killed earlier save left a staging folder (its process is gone)
    dead = tmp_path / ".partial-run-999999999-deadbeef"
    dead.mkdir()
    (out / ".partial-xyz").mkdir()
    only_summary = ["output.figures=false", "output.csv=false", "output.report=false"]
    assert main([*base, *(a for o in only_summary for a in ("--set", o))]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def test_out_with_foreign_files_needs_force(tmp_path, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    base = [
        "run",
        "sensorless",
        "--out",
        str(out),
        "-q",
        "--set",
        "simulation.t_end_s=0.01",
        "--set",
        "output.figures=false",
    ]
    assert main(base) == cli.EXIT_BAD_INPUT
    assert "--force" in _fail_line(capsys)
    assert (out / "notes.txt").read_text() == "keep me"
    assert main([*base, "--force"]) == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "report.html",
        "summary.json",
        "timeseries.csv",
    ]


# ------------------------------------------------------------------------------------------
# 6. rules for every field


NONSENSE = [
    ("simulation.substeps=1e18", "simulation.substeps"),
    ("simulation.substeps=1e300", "simulation.substeps"),
    ("simulation.log_every=1e30", "simulation.log_every"),
    ("control.speed_kp=-1", "control.speed_kp"),
    ("control.current_kp=-5", "control.current_kp"),
    ("control.speed_ki=-1", "control.speed_ki"),
    ("control.current_ki=-1", "control.current_ki"),
    ("mras.K1=-1", "mras.K1"),
    ("mras.K2=-1", "mras.K2"),
    ("load.viscous_Nms=-0.1", "load.viscous_Nms"),
    ("load.fan_Nms2=-0.1", "load.fan_Nms2"),
    ("plant.thermal.theta_amb_C=-300", "plant.thermal.theta_amb_C"),
    ("plant.thermal.theta_init_C=-273.15", "plant.thermal.theta_init_C"),
    ("plant.thermal.theta_ref_C=-1000", "plant.thermal.theta_ref_C"),
    ("compensator.R2_min_ohm=2.0", "compensator.R2_min_ohm"),  # above the default max 1.63
    ("compensator.R2_max_ohm=0.1", "compensator.R2_max_ohm"),  # below the default min 0.41
    ("injection.amplitude_A=1e300", "injection.amplitude_A"),
    ("injection.amplitude_A=50", "injection.amplitude_A"),
    ("sensor.seed=1e30", "sensor.seed"),
    ("machine.pole_pairs=1e6", "machine.pole_pairs"),
    ("injection.frequency_Hz=1e-300", "injection.frequency_Hz"),
]


@pytest.mark.parametrize(("setting", "field"), NONSENSE, ids=[n[0] for n in NONSENSE])
def test_nonsense_values_are_refused_naming_the_field(setting, field):
    with pytest.raises(ConfigError) as exc:
        build_arrays(Scenario.read("sensorless", [setting]))
    assert exc.value.field == field, str(exc.value)


def test_thermal_coefficients_keep_resistances_positive():
    with pytest.raises(ConfigError, match="theta_amb_C"):
        Scenario.read(
            "sensorless", ["plant.thermal.alpha1_per_K=0.1", "plant.thermal.theta_amb_C=-200"]
        )


hypothesis = pytest.importorskip("hypothesis")
st = pytest.importorskip("hypothesis.strategies")


def _schema_keys() -> list[tuple[str, ...]]:
    from imdrive.config.schema import setting_paths

    return sorted(setting_paths())


_SCALARS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-1e300, max_value=1e300),
    st.sampled_from([0, 1, -1, 1e-300, 1e300, -1e300, 2**63, 2**64, 10**30, 0.5, 2.0]),
    st.integers(),
    st.booleans(),
    st.text(max_size=12),
    st.sampled_from(["vector", "mras", "demodulated", "switching", "imposed", "paper"]),
)
_VALUES = st.recursive(
    _SCALARS,
    lambda inner: st.one_of(
        st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=6,
)


@st.composite
def _scenario_dicts(draw):
    keys = _schema_keys()
    data: dict = {}
    for _ in range(draw(st.integers(0, 5))):
        if draw(st.booleans()):
            path = draw(st.sampled_from(keys))
        else:  # random structure: unknown keys, sections as values, deep nesting
            path = tuple(draw(st.lists(st.text(min_size=0, max_size=5), min_size=1, max_size=3)))
        node = data
        for p in path[:-1]:
            nxt = node.setdefault(p, {})
            if not isinstance(nxt, dict):
                break
            node = nxt
        else:
            node[path[-1]] = draw(_VALUES)
    return data


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@hypothesis.settings(max_examples=300, deadline=None, derandomize=True)
@hypothesis.given(_scenario_dicts())
def test_loader_gives_a_clean_error_or_a_scenario_that_builds(data):
    try:
        sc = Scenario.from_dict(data)
        build_arrays(sc)
    except ConfigError as exc:
        assert exc.field and isinstance(exc.field, str)
        assert "\n" not in str(exc)


# ------------------------------------------------------------------------------------------
# 7. size guard


HUGE = TINY.replace(
    "R2_ratio = [0.8, 1.0, 1.2]\nspeed_rpm = [300, 600]",
    "R2_ratio = { min = 0.5, max = 1.5, num = 1000 }\n"
    "speed_rpm = { min = 0, max = 1500, num = 1000 }\n"
    "load_Nm = { min = 0, max = 12, num = 1000 }",
)


def test_a_billion_run_sweep_is_refused_at_once(tmp_path, capsys):
    f = tmp_path / "huge.toml"
    f.write_text(HUGE)
    t0 = time.perf_counter()
    rc = main(["sweep", str(f), "--dry-run"])
    assert time.perf_counter() - t0 < 1.0
    assert rc == cli.EXIT_BAD_INPUT
    assert "limit" in _fail_line(capsys)
    with pytest.raises(ConfigError, match="samples"):
        parse_sweep(TINY + "samples = 1000000000\n")


def test_a_million_run_dry_run_answers_in_seconds(tmp_path, capsys):
    f = tmp_path / "million.toml"
    f.write_text(HUGE.replace("num = 1000 }\n", "num = 100 }\n"))
    t0 = time.perf_counter()
    rc = main(["sweep", str(f), "--dry-run"])
    assert time.perf_counter() - t0 < 10.0
    assert rc == 0
    assert "1000000 runs" in capsys.readouterr().out


def test_max_runs_is_a_setting(tmp_path, capsys):
    f = tmp_path / "tiny.toml"
    f.write_text(TINY)
    assert main(["sweep", str(f), "--dry-run", "--max-runs", "5"]) == cli.EXIT_BAD_INPUT
    assert "limit" in _fail_line(capsys)
    assert main(["sweep", str(f), "--dry-run", "--max-runs", "6"]) == 0


# ------------------------------------------------------------------------------------------
# 8. smaller


def _strict_json(text: str):
    def refuse(name):
        raise ValueError(f"bare {name} in JSON")

    return json.loads(text, parse_constant=refuse)


def test_diverged_summary_is_strict_json(tmp_path):
    res = __import__("imdrive.run.simulate", fromlist=["simulate"]).simulate(
        Scenario.read(
            "sensorless",
            [
                "control.current_kp=150.0",
                "inverter.Vdc_V=1e5",
                "simulation.t_end_s=1.0",
                "output.figures=false",
            ],
        )
    )
    assert res.diverged
    res.save(tmp_path / "r")
    s = _strict_json((tmp_path / "r" / "summary.json").read_text())
    assert s["diverged"] is True
    if any(v is None for v in s["final"].values()):
        assert "null" in s["note"]


def test_byte_order_mark_is_accepted(tmp_path):
    f = tmp_path / "bom.toml"
    f.write_bytes(b"\xef\xbb\xbf" + b'name = "bom"\n[simulation]\nt_end_s = 0.01\n')
    assert Scenario.read(str(f)).name == "bom"
    s = tmp_path / "bom-sweep.toml"
    s.write_bytes(b"\xef\xbb\xbf" + TINY.encode())
    assert load_sweep(str(s)).name == "tiny"


def test_empty_out_is_refused(capsys):
    assert main(["run", "sensorless", "--out", "", "-q"]) == cli.EXIT_BAD_INPUT
    assert "--out" in _fail_line(capsys)


def test_unknown_sweep_base_names_base():
    with pytest.raises(ConfigError) as exc:
        parse_sweep(TINY.replace('base = "sensorless"', 'base = "no-such-preset"'))
    assert exc.value.field == "base"


def test_manifest_complete_only_after_the_figures(tmp_path, monkeypatch):
    def broken(*a, **k):
        raise OSError(errno.EIO, "Input/output error", "figures")

    monkeypatch.setattr("imdrive.sweep.run.save_heatmaps", broken)
    out = tmp_path / "store"
    with pytest.raises(OSError):
        run_sweep(parse_sweep(TINY), out, progress=False)
    assert json.loads((out / "manifest.json").read_text())["complete"] is False
    assert math.isfinite(pd.read_parquet(out / "runs.parquet")["speed_error_rpm"].iloc[0])


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_final_values_are_at_t_end_whatever_log_every():
    from imdrive.run.simulate import simulate

    common = ["simulation.t_end_s=0.05", "output.figures=false"]
    every = simulate(Scenario.read("sensorless", [*common, "simulation.log_every=1"]))
    for le in (7, 10**6):
        sparse = simulate(Scenario.read("sensorless", [*common, f"simulation.log_every={le}"]))
        assert sparse.final_values() == every.final_values()
        assert sparse.summary()["final"]["time_s"] == pytest.approx(0.05)
        for k in every.columns:  # the logged rows are unchanged
            assert np.array_equal(sparse[k], every[k][::le]), k
