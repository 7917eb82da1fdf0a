"""The kernel cache follows what each kernel depends on, and nothing else (imdrive._cache)."""

from __future__ import annotations

import multiprocessing as mp
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from data.compiles import COUNT_COMPILES

import imdrive
from imdrive import _cache
from imdrive.kernels.engine import run_drive

PKG = Path(imdrive.__file__).resolve().parent


@pytest.fixture
def copy(tmp_path, monkeypatch):
    """A copy of the package's sources (no caches), and a cache root of the test's own."""
    monkeypatch.setenv("IMDRIVE_CACHE_DIR", str(tmp_path / "cache"))
    dst = tmp_path / "src" / "imdrive"
    shutil.copytree(PKG, dst, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    return dst


def _keys(pkg: Path) -> dict[str, str]:
    _cache.module_keys.cache_clear()
    return _cache.module_keys(pkg / "kernels")


def _edit(path: Path) -> None:
    path.write_text(path.read_text() + "\n# edited\n")


def test_keys_follow_contents_not_paths(copy):
    assert _keys(copy) == _keys(PKG)  # another folder, the same code: the same cache
    assert _keys(copy) == _keys(copy)  # from the memo file as from the sources


def test_a_damaged_memo_is_computed_again(copy, tmp_path):
    before = _keys(copy)
    for memo in (tmp_path / "cache").glob("module-keys-*.json"):
        memo.write_text("{not json")
    assert _keys(copy) == before


def test_an_edit_outside_the_kernels_changes_no_key(copy):
    before = _keys(copy)
    for rel in ("config/scenario.py", "run/simulate.py", "cli/run.py", "_cache.py"):
        _edit(copy / rel)
    assert _keys(copy) == before


def test_a_kernel_edit_changes_the_keys_of_its_importers_only(copy):
    before = _keys(copy)
    _edit(copy / "kernels" / "estimators" / "mras.py")
    after = _keys(copy)
    changed = {m for m in before if before[m] != after[m]}
    # what compiles the MRAS in: itself, the registry's generic step, the stages, the engine,
    # the batch and stability kernels that call the engine
    for m in ("estimators.mras", "estimators.registry", "stages", "engine", "batch", "linearise"):
        assert f"imdrive.kernels.{m}" in changed, m
    # what does not: the machine model, records, the other estimators' own helpers
    for m in ("machine", "records", "model", "fuzzy", "estimators.common", "saturation"):
        assert f"imdrive.kernels.{m}" not in changed, m


def test_a_stability_kernel_edit_leaves_the_drive_cached(copy):
    before = _keys(copy)
    _edit(copy / "kernels" / "linearise.py")
    after = _keys(copy)
    assert {m for m in before if before[m] != after[m]} == {"imdrive.kernels.linearise"}


def test_a_user_estimator_changes_the_registry_key_through_its_import(copy):
    # a new estimator module that registers: the registry's generic entry points compile its
    # step, so the registry (and all that inline it) must follow it
    before = _keys(copy)
    (copy / "kernels" / "estimators" / "zz_new.py").write_text(
        "from imdrive.kernels.estimators.registry import register_kernel  # noqa: F401\n"
    )
    after = _keys(copy)
    assert (
        after["imdrive.kernels.estimators.registry"]
        != (before["imdrive.kernels.estimators.registry"])
    )
    assert after["imdrive.kernels.engine"] != before["imdrive.kernels.engine"]
    assert after["imdrive.kernels.machine"] == before["imdrive.kernels.machine"]


def test_the_versions_are_part_of_the_key(copy, monkeypatch):
    before = _keys(copy)
    monkeypatch.setattr(_cache, "_versions", lambda: b"numba=0.0")
    assert set(_keys(copy).values()).isdisjoint(before.values())


def test_old_folders_are_pruned(tmp_path):
    now = time.time()
    day = 86400.0
    for i in range(5):  # used 0, 3, 6, 9 and 12 days ago
        for m in ("imdrive.kernels.engine", "imdrive.kernels.machine"):
            p = tmp_path / f"{m}-{i:016x}"
            p.mkdir()
            os.utime(p, (now - 3 * day * i, now - 3 * day * i))
    (tmp_path / "kernels-0123456789abcdef").mkdir()  # imdrive 0.2's single-hash folder
    (tmp_path / "someone-elses").mkdir()
    (tmp_path / "notes.txt").write_text("x")
    # the 3 most recent are kept whatever their age; beyond them the 9- and 12-day-old ones go
    removed = _cache.prune(tmp_path, keep=3, max_age_days=7, now=now)
    assert len(removed) == 2 * 2 + 1
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted(
        [f"imdrive.kernels.{m}-{i:016x}" for m in ("engine", "machine") for i in range(3)]
        + ["someone-elses", "notes.txt"]
    )


def test_folders_in_use_on_several_branches_are_kept_up_to_a_cap(tmp_path):
    # five worktrees used today: all kept (KEEP alone evicted two at every switch) ...
    now = time.time()
    for i in range(12):
        p = tmp_path / f"imdrive.kernels.engine-{i:016x}"
        p.mkdir()
        os.utime(p, (now - 60 * i, now - 60 * i))
    removed = _cache.prune(tmp_path, keep=3, max_age_days=7, max_recent=5, now=now)
    # ... up to the cap: the five most recent stay
    assert sorted(p.name for p in removed) == [
        f"imdrive.kernels.engine-{i:016x}" for i in range(5, 12)
    ]


def test_the_engine_caches_in_its_module_folder():
    where = Path(run_drive._cache._cache_path)
    assert where == _cache.module_folder("imdrive.kernels.engine")
    assert where.parent == _cache.cache_root()


def test_a_function_numba_cannot_cache_gets_numba_s_warning_not_a_crash():
    # numba refuses to cache code with dynamic globals (a ctypes pointer, or what NUMBA_OPT=0
    # leaves unoptimised) and names the source file in its warning: the locator must know it
    from types import SimpleNamespace

    from numba.core.errors import NumbaWarning

    impl = run_drive._cache._impl
    cres = SimpleNamespace(
        lifted=(),
        library=SimpleNamespace(has_dynamic_globals=True),
        fndesc=SimpleNamespace(qualname="run_drive"),
    )
    with pytest.warns(NumbaWarning, match="Cannot cache compiled function"):
        assert impl.check_cachable(cres) is False
    assert impl.locator._py_file.endswith("engine.py")


def _save_entries(folder: str, who: str, n: int, start: float) -> None:
    from numba.core.caching import IndexDataCacheFile

    index = IndexDataCacheFile(folder, "kernel-1.py", "stamp")
    while time.time() < start:  # both processes save at the same moment
        pass
    for i in range(n):
        index.save((who, i), (who, i))


@pytest.mark.skipif("fork" not in mp.get_all_start_methods(), reason="needs fork")
def test_processes_saving_to_one_index_at_once_keep_every_entry_and_its_own_code(
    tmp_path, monkeypatch
):
    # numba's own save loses ~40 % of the entries here and points 6-8 of 80 at the other
    # process's data (the wrong machine code for a signature); under the package's cache
    # root the save holds a lock
    monkeypatch.setenv("IMDRIVE_CACHE_DIR", str(tmp_path))
    folder = tmp_path / "imdrive.kernels.engine-0"
    folder.mkdir()
    ctx = mp.get_context("fork")
    start = time.time() + 0.5
    procs = [ctx.Process(target=_save_entries, args=(str(folder), w, 40, start)) for w in "AB"]
    for p in procs:
        p.start()
    for p in procs:
        p.join(60)
        assert p.exitcode == 0
    from numba.core.caching import IndexDataCacheFile

    index = IndexDataCacheFile(str(folder), "kernel-1.py", "stamp")
    kept = index._load_index()
    assert len(kept) == 80
    assert all(index.load(key) == key for key in kept)


RUN = COUNT_COMPILES  # prints the functions compiled for a short drive


@pytest.mark.slow
def test_an_edit_of_config_or_run_recompiles_nothing(tmp_path):
    # the package copied elsewhere: the same kernels find the cache of the installed package
    # (keys are of contents), so only a cold cache compiles here, once
    dst = tmp_path / "src" / "imdrive"
    shutil.copytree(PKG, dst, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    env = {**os.environ, "PYTHONPATH": str(tmp_path / "src")}

    def run() -> int:
        res = subprocess.run(
            [sys.executable, "-c", RUN], cwd=tmp_path, env=env, capture_output=True, text=True
        )
        assert res.returncode == 0, res.stderr[-3000:]
        return len(res.stdout.split())

    run()  # warms the cache if it is cold
    for rel in ("config/scenario.py", "config/machine.py", "run/simulate.py", "run/build.py"):
        _edit(dst / rel)
    assert run() == 0
    # and nothing was written into the (copied) source tree
    assert not [p for p in dst.rglob("*") if p.suffix in (".nbi", ".nbc")]
