"""The run's figures are written by the output rule for one file (issue 40, class 3/13:
``save_figures`` wrote with ``fig.savefig`` straight into any path): a missing folder or a
special file in a figure's place is refused with a ConfigError naming it, before anything is
written there, and a written figure leaves no temporary file behind."""

from __future__ import annotations

import os

import pytest

from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.run.plots import save_figures
from imdrive.run.simulate import simulate


@pytest.fixture(scope="module")
def res():
    return simulate(Scenario.read("sensorless", ["simulation.t_end_s=0.3"]))


def test_figures_are_written_whole(tmp_path, res):
    paths = save_figures(res, tmp_path)
    assert {p.name for p in paths} == {p.name for p in tmp_path.iterdir()}
    assert all(p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in paths)


def test_a_missing_folder_is_refused(tmp_path, res):
    with pytest.raises(ConfigError, match="out_dir"):
        save_figures(res, tmp_path / "nosuch")
    assert not (tmp_path / "nosuch").exists()


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_in_a_figures_place_is_refused_and_kept(tmp_path, res):
    fifo = tmp_path / "speed.png"
    os.mkfifo(fifo)
    with pytest.raises(ConfigError, match="speed.png"):
        save_figures(res, tmp_path)
    assert fifo.is_fifo()  # not replaced by a regular file
    assert [p.name for p in tmp_path.iterdir()] == ["speed.png"]  # nothing else written


def test_a_link_is_written_through(tmp_path, res):
    target = tmp_path / "kept.png"
    target.write_bytes(b"old")
    out = tmp_path / "out"
    out.mkdir()
    (out / "speed.png").symlink_to(target)
    save_figures(res, out)
    assert (out / "speed.png").is_symlink()
    assert target.read_bytes()[:4] == b"\x89PNG"
