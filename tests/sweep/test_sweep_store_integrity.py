"""The sweep store's manifest and chunk checksums (issue 40, class 9): a manifest that is not
one is refused naming the file; a chunk edited after it was written (a metric value, which the
structural checks cannot see) is found by its sha256 and recomputed, never marked complete."""

from __future__ import annotations

import hashlib
import json

import pandas as pd
import pytest
from data.inprocess import imdrive_here
from data.sweeps import TINY

from imdrive.errors import ConfigError, EnvironmentFailure
from imdrive.sweep import parse_sweep, run_sweep
from imdrive.sweep.store import Store

QUIET = {"progress": False, "figures": False, "report": False}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("ref") / "store"
    return run_sweep(parse_sweep(TINY), out, **QUIET)


@pytest.fixture
def store(tmp_path, reference):
    out = tmp_path / "store"
    run_sweep(parse_sweep(TINY), out, **QUIET)
    return out


def _edit_metric(chunk):
    df = pd.read_parquet(chunk)
    df.assign(speed_error_rpm=df["speed_error_rpm"] + 100.0).to_parquet(chunk, index=False)


def test_manifest_records_each_chunks_sha256(store):
    man = json.loads((store / "manifest.json").read_text())
    assert sorted(man["chunk_sha256"]) == ["0", "1", "2"]
    for j, digest in man["chunk_sha256"].items():
        data = (store / "chunks" / f"chunk-{int(j):06d}.parquet").read_bytes()
        assert hashlib.sha256(data).hexdigest() == digest


def test_an_edited_metric_is_recomputed_on_resume(store, reference):
    _edit_metric(store / "chunks" / "chunk-000001.parquet")
    notes: list[str] = []
    df = run_sweep(parse_sweep(TINY), store, resume=True, notice=notes.append, **QUIET)
    assert any("chunk 1" in n and "sha256" in n and "recomputed" in n for n in notes), notes
    pd.testing.assert_frame_equal(df, reference)
    pd.testing.assert_frame_equal(pd.read_parquet(store / "runs.parquet"), reference)
    assert json.loads((store / "manifest.json").read_text())["complete"] is True


def test_a_chunk_edited_while_the_sweep_runs_is_recomputed(tmp_path, reference, monkeypatch):
    write = Store.write_chunk

    def write_then_edit_chunk_0(self, j, df):
        write(self, j, df)
        if j == 2:  # the last chunk: chunk 0 is edited before the table is assembled
            _edit_metric(self.chunk_path(0))

    monkeypatch.setattr(Store, "write_chunk", write_then_edit_chunk_0)
    notes: list[str] = []
    df = run_sweep(parse_sweep(TINY), tmp_path / "s", notice=notes.append, **QUIET)
    assert any("chunk 0" in n and "sha256" in n for n in notes), notes
    pd.testing.assert_frame_equal(df, reference)


def test_consolidate_refuses_an_edited_chunk(store):
    sweep = parse_sweep(TINY)
    st = Store(store)
    st.read_manifest()
    _edit_metric(store / "chunks" / "chunk-000002.parquet")
    with pytest.raises(EnvironmentFailure, match="chunk-000002.*sha256"):
        st.consolidate(sweep, 2)


MANIFESTS = {
    "a JSON list": "[1, 2, 3]",
    "deeply nested": "[" * 100_000 + "]" * 100_000,
    "a string": '"manifest"',
    "no fingerprint": '{"chunk_size": 2}',
    "chunk size as text": '{"fingerprint": "x", "chunk_size": "2"}',
    "bad checksum table": '{"fingerprint": "x", "chunk_size": 2, "chunk_sha256": {"0": 5}}',
    "not UTF-8": b'{"fingerprint": "\xff"}',
}


@pytest.mark.parametrize("text", MANIFESTS.values(), ids=MANIFESTS.keys())
def test_a_manifest_that_is_not_one_is_refused_naming_the_file(store, text):
    p = store / "manifest.json"
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(ConfigError) as exc:
        run_sweep(parse_sweep(TINY), store, resume=True, **QUIET)
    assert exc.value.field == "--resume"
    assert str(p) in str(exc.value) and "\n" not in str(exc.value)


def test_cli_resume_over_a_list_manifest_exits_2_naming_it(store, tmp_path):
    """Through ``main`` in this process (``data.inprocess``)."""
    f = tmp_path / "tiny.toml"
    f.write_text(TINY)
    (store / "manifest.json").write_text("[]")
    proc = imdrive_here("sweep", f, "--out", store, "--resume", "-q", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "manifest.json" in lines[0]
    assert (store / "manifest.json").read_text() == "[]"  # refused before writing
