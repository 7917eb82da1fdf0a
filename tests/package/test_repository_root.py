"""The repository's top level holds what a checkout needs and nothing else (issue 39: four
scratch files, ``batch.pid``, ``bg1.pid``, ``k.pid`` and ``m2.txt``, had been committed there).

Read from ``git ls-files``, so files a developer keeps untracked (an ``out/`` folder, a local
script) never fail it; skipped outside a git checkout (an installed sdist)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: the committed top-level entries; a new one is added here on purpose, with its reason
EXPECTED = {
    ".ci",  # the CI entry point (README: `.ci/run`)
    ".gitignore",
    "CHANGELOG.md",
    "README.md",
    "benchmarks",
    "docs",
    "mkdocs.yml",  # the docs site
    "mkdocs_hooks.py",
    "pyproject.toml",
    "src",
    "tests",
}


def _tracked_top_level() -> set[str]:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    out = subprocess.run(
        ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True, timeout=60
    ).stdout.decode()
    return {path.split("/", 1)[0] for path in out.split("\0") if path}


def test_no_scratch_file_is_committed_at_the_root():
    unexpected = _tracked_top_level() - EXPECTED
    assert not unexpected, (
        f"committed at the repository root, not in EXPECTED: {sorted(unexpected)}"
    )


def test_the_allow_list_has_nothing_stale():
    assert EXPECTED <= _tracked_top_level()
