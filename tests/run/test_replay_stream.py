"""The replay's pipeline (imdrive.run.replay_stream, the threads of imdrive.run.replay).

Chunks and threads change nothing: a replay in many small chunks with every estimator in a
thread of its own gives bit for bit the estimates, the summary and the file of one in a
single chunk on one thread. An error in a late chunk, raised in the reading thread, still
leaves nothing written; the files are written byte-stream split without a dictionary.
"""

from __future__ import annotations

import threading

import numpy as np
import pyarrow.parquet as pq
import pytest

import imdrive as im
from imdrive.errors import ConfigError
from imdrive.run.replay import replay
from imdrive.run.replay_stream import read_ahead
from imdrive.run.simulate import simulate

SHORT = {
    "simulation.t_end_s": 0.3,
    "control.speed_ref_rpm": {"initial": 0, "changes": [{"at": 0.05, "to": 600, "over": 0.2}]},
}
THREE = "mras,afo,ekf"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    res = simulate(im.Scenario.read("sensorless").with_overrides(SHORT), record=True)
    folder = tmp_path_factory.mktemp("rec") / "run"
    res.save(folder, formats=["recording"])
    return folder


def estimates(folder) -> dict:
    t = pq.read_table(str(folder / "timeseries.parquet"))
    return {n: t[n].to_numpy() for n in t.column_names}


@pytest.mark.slow  # 1.5 s or more on 2 cores (5.8 s measured 2026-11-29)
def test_chunks_and_threads_change_nothing(run_dir, tmp_path, monkeypatch):
    many = replay(run_dir, estimators=THREE, out=tmp_path / "many", chunk_rows=257)
    assert many.summary["rows_replayed"] > 10 * 257  # many chunks, several under way at once
    with monkeypatch.context() as m:
        m.setattr("os.cpu_count", lambda: 1)  # no threads for the estimators
        serial = replay(run_dir, estimators=THREE, out=tmp_path / "serial", chunk_rows=257)
        one = replay(run_dir, estimators=THREE, out=tmp_path / "one", chunk_rows=1 << 20)
    a = estimates(tmp_path / "many")
    assert np.ptp(a["speed_est_ekf_rpm"]) > 100.0  # the estimates moved
    for other in ("serial", "one"):
        b = estimates(tmp_path / other)
        assert list(a) == list(b)
        for name in a:
            np.testing.assert_array_equal(a[name], b[name], err_msg=f"{other}: {name}")
    assert many.summary["estimators"] == serial.summary["estimators"]  # the threads: nothing
    for name, s in one.summary["estimators"].items():  # the chunks: the sums' rounding
        t = many.summary["estimators"][name]
        assert (s["status"], s["R2_hat_end_ohm"]) == (t["status"], t["R2_hat_end_ohm"])
        for k, v in s["speed_error_rpm"].items():
            assert t["speed_error_rpm"][k] == pytest.approx(v, rel=1e-12), (name, k)
    mem = replay(run_dir, estimators=THREE, chunk_rows=1000)  # in memory, no file
    for name in a:
        np.testing.assert_array_equal(mem.signals[name], a[name], err_msg=name)


def test_a_bad_row_in_a_late_chunk_leaves_nothing(run_dir, tmp_path):
    import pyarrow as pa

    t = pq.read_table(str(run_dir / "recording.parquet"))
    cols = {n: t[n].to_numpy().copy() for n in t.column_names}
    cols["i_alpha_meas_A"][2500] = np.nan
    bad = tmp_path / "bad.parquet"
    pq.write_table(pa.table(cols), str(bad))
    with pytest.raises(ConfigError, match="column i_alpha_meas_A row 2500"):
        replay(bad, "sensorless", THREE, tmp_path / "out", chunk_rows=200)
    assert not (tmp_path / "out").exists()
    assert not [th for th in threading.enumerate() if th.name.startswith("imdrive-replay")]


def test_read_ahead_gives_the_items_then_the_error_in_order():
    def items():
        yield 1
        yield 2
        raise ConfigError("x", "bad row")

    got = []
    with pytest.raises(ConfigError, match="bad row"):
        for item in read_ahead(items()):
            got.append(item)
    assert got == [1, 2]
    it = read_ahead(iter(range(100)))
    assert next(it) == 0
    it.close()  # stops the thread, which waits to hand over the next item
    assert not [th for th in threading.enumerate() if th.name == "imdrive-replay-read"]


def test_files_are_byte_stream_split_and_exact(run_dir, tmp_path):
    replay(run_dir, estimators="mras", out=tmp_path / "rep")
    for path in (run_dir / "recording.parquet", tmp_path / "rep" / "timeseries.parquet"):
        meta = pq.ParquetFile(str(path)).metadata
        col = meta.row_group(0).column(0)
        assert "BYTE_STREAM_SPLIT" in col.encodings
        assert "RLE_DICTIONARY" not in col.encodings
    res = simulate(im.Scenario.read("sensorless").with_overrides(SHORT), record=True)
    t = pq.read_table(str(run_dir / "recording.parquet"))
    for name, v in res.recording.items():
        np.testing.assert_array_equal(t[name].to_numpy(), v, err_msg=name)


def test_an_error_in_an_estimators_thread_stops_every_thread(run_dir, tmp_path, monkeypatch):
    from imdrive.run import replay as rp

    run = rp._Estimator.run
    calls = []

    def failing(self, rows, enc):
        calls.append(self.name)
        if len(calls) == 13:
            raise RuntimeError("estimator failed")
        return run(self, rows, enc)

    monkeypatch.setattr(rp._Estimator, "run", failing)
    with pytest.raises(RuntimeError, match="estimator failed"):
        replay(run_dir, estimators=THREE, out=tmp_path / "out", chunk_rows=200)
    assert len(calls) >= 13
    assert not (tmp_path / "out").exists()
    assert not [th for th in threading.enumerate() if th.name.startswith("imdrive-replay")]
