"""Atomic writes (imdrive._io): a file or a folder's set of files is whole, or not there."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from imdrive import _io
from imdrive._io import (
    AtomicFolder,
    atomic_path,
    atomic_write_bytes,
    atomic_write_text,
    remove_partials,
)


class Boom(RuntimeError):
    pass


def _names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# ------------------------------------------------------------------------------------------
# one file


def test_atomic_write_creates_and_replaces(tmp_path):
    p = tmp_path / "a.json"
    atomic_write_text(p, "one")
    assert p.read_text() == "one"
    atomic_write_text(p, "two")
    assert p.read_text() == "two"
    atomic_write_bytes(tmp_path / "b.bin", b"\x00\x01")
    assert (tmp_path / "b.bin").read_bytes() == b"\x00\x01"
    assert _names(tmp_path) == ["a.json", "b.bin"]


def test_exception_mid_write_leaves_the_old_file_and_no_temporary(tmp_path):
    p = tmp_path / "table.parquet"
    p.write_text("old")
    with pytest.raises(Boom), atomic_path(p) as tmp:
        assert tmp.parent == tmp_path and tmp.suffix == ".parquet" and tmp != p
        tmp.write_text("half of the new")
        raise Boom
    assert p.read_text() == "old"
    assert _names(tmp_path) == ["table.parquet"]
    # a new file that fails is not created at all
    with pytest.raises(Boom), atomic_path(tmp_path / "new.txt") as tmp:
        tmp.write_text("x")
        raise Boom
    assert _names(tmp_path) == ["table.parquet"]


def test_temporary_names_are_recognised_as_partial(tmp_path):
    with atomic_path(tmp_path / "chunk-000001.parquet") as tmp:
        assert _io.is_partial(tmp.name)
        assert not tmp.name.startswith("chunk-")  # never mistaken for a finished chunk
        tmp.write_text("x")
    assert not _io.is_partial("chunk-000001.parquet")
    assert not _io.is_partial("summary.json")


# ------------------------------------------------------------------------------------------
# a set of files


def test_folder_write_moves_every_file_the_marker_last(tmp_path):
    out = tmp_path / "run"
    with AtomicFolder(out, "summary.json") as staging:
        assert staging.path.parent == out
        for name in ("b.png", "a.csv", "summary.json"):
            (staging.path / name).write_text(name)
        assert not (out / "summary.json").exists()  # nothing visible before the end
    assert [p.name for p in staging.written] == ["a.csv", "b.png", "summary.json"]
    assert _names(out) == ["a.csv", "b.png", "summary.json"]
    assert (out / "a.csv").read_text() == "a.csv"


def test_exception_mid_folder_write_leaves_nothing_that_looks_complete(tmp_path):
    out = tmp_path / "run"
    with pytest.raises(Boom), AtomicFolder(out, "summary.json") as staging:
        (staging.path / "timeseries.csv").write_text("1,2\n")
        (staging.path / "summary.json").write_text("{}")
        raise Boom
    assert _names(out) == []  # no file, no staging folder
    # an earlier complete write is left as it was
    with AtomicFolder(out, "summary.json") as staging:
        (staging.path / "timeseries.csv").write_text("old")
        (staging.path / "summary.json").write_text("old")
    with pytest.raises(Boom), AtomicFolder(out, "summary.json") as staging:
        (staging.path / "timeseries.csv").write_text("new")
        raise Boom
    assert _names(out) == ["summary.json", "timeseries.csv"]
    assert (out / "timeseries.csv").read_text() == "old"


def test_failure_while_moving_removes_the_old_marker(tmp_path, monkeypatch):
    out = tmp_path / "run"
    with AtomicFolder(out, "summary.json") as staging:
        for name in ("a.csv", "b.png", "summary.json"):
            (staging.path / name).write_text("old")
    real_replace = os.replace

    def replace(src, dst):  # the disk fills up after the first file
        if Path(dst).name == "b.png":
            raise OSError("no space left on device")
        real_replace(src, dst)

    monkeypatch.setattr(_io.os, "replace", replace)
    with pytest.raises(OSError), AtomicFolder(out, "summary.json") as staging:
        for name in ("a.csv", "b.png", "summary.json"):
            (staging.path / name).write_text("new")
    # a.csv is new, b.png old: the folder must not look complete
    assert (out / "a.csv").read_text() == "new"
    assert not (out / "summary.json").exists()
    assert not any(_io.is_partial(n) for n in _names(out))


def test_folder_write_without_its_marker_moves_nothing(tmp_path):
    out = tmp_path / "run"
    with pytest.raises(FileNotFoundError), AtomicFolder(out, "summary.json") as staging:
        (staging.path / "timeseries.csv").write_text("x")
    assert _names(out) == []


def test_killed_writer_leaves_only_partials_which_are_removable(tmp_path):
    out = tmp_path / "run"
    child = textwrap.dedent(
        f"""
        import os
        from pathlib import Path
        from imdrive._io import AtomicFolder, atomic_path
        out = Path({str(out)!r})
        out.mkdir()
        with atomic_path(out / "manifest.json") as tmp:
            tmp.write_text("{{")
            with AtomicFolder(out, "summary.json") as staging:
                (staging.path / "timeseries.csv").write_text("1,2")
                (staging.path / "summary.json").write_text("{{}}")
                os._exit(9)  # killed: no cleanup runs
        """
    )
    proc = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True)
    assert proc.returncode == 9, proc.stderr
    names = _names(out)
    assert "summary.json" not in names and "manifest.json" not in names
    assert names and all(_io.is_partial(n) for n in names)
    remove_partials(out)
    assert _names(out) == []
    remove_partials(tmp_path / "missing")  # no folder: nothing to do


def test_io_and_progress_import_nothing_of_imdrive():
    src = Path(_io.__file__).parent
    for name in ("_io.py", "_progress.py"):
        tree = ast.parse((src / name).read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                mods = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                mods = [node.module or ""]
            else:
                continue
            assert not any(m == "imdrive" or m.startswith("imdrive.") for m in mods), name
