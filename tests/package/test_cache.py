"""The kernel cache folder follows every source file of the package (see imdrive._cache)."""

from __future__ import annotations

import shutil
from pathlib import Path

import imdrive
from imdrive import _cache
from imdrive.kernels.engine import run_drive


def test_any_source_change_gives_a_new_cache_folder(tmp_path):
    pkg = Path(imdrive.__file__).parent
    copy = tmp_path / "imdrive"
    shutil.copytree(pkg, copy, ignore=shutil.ignore_patterns("__pycache__"))
    h0 = _cache.source_hash(copy)
    assert _cache.source_hash(copy) == h0  # stable
    assert h0 == _cache.source_hash(pkg)
    # a change in a kernel the engine calls (not the engine's own file) must invalidate it
    mras = copy / "kernels" / "estimators" / "mras.py"
    mras.write_text(mras.read_text() + "\n# changed\n")
    assert _cache.source_hash(copy) != h0


def test_kernels_cache_in_the_hashed_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("IMDRIVE_CACHE_DIR", str(tmp_path))
    folder = _cache.cache_dir()
    assert folder.parent == tmp_path
    assert folder.name == f"kernels-{_cache.source_hash()}"
    # the engine was decorated under the package's folder, not numba's default __pycache__
    assert Path(run_drive._cache._cache_path).parent.name.startswith("kernels-")
