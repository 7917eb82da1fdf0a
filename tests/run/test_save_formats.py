"""Exports are reachable: ``res.save(formats=[...])``, ``imdrive run --format``, and the
``formats`` extra (xarray) behind ``res.to_xarray()``."""

from __future__ import annotations

import pytest

import imdrive as im
from imdrive.cli import main
from imdrive.errors import ConfigError


@pytest.fixture(scope="module")
def res():
    return im.simulate(im.Scenario.read("sensorless").with_overrides({"simulation.t_end_s": 0.3}))


def test_save_writes_exactly_the_formats_asked(res, tmp_path):
    paths = res.save(tmp_path / "a", formats=["parquet", "mat"])
    assert sorted(p.name for p in paths) == ["summary.json", "timeseries.mat", "timeseries.parquet"]
    import scipy.io

    mat = scipy.io.loadmat(tmp_path / "a" / "timeseries.mat")
    assert mat["speed_rpm"].size == len(res.time_s)


def test_save_rejects_an_unknown_format(res, tmp_path):
    with pytest.raises(ConfigError, match="no output format 'netcdf'"):
        res.save(tmp_path / "b", formats=["netcdf"])
    assert not (tmp_path / "b").exists()


def test_cli_format(tmp_path, capsys):
    out = tmp_path / "r"
    sets = ["--set", "simulation.t_end_s=0.2"]
    assert (
        main(["run", "sensorless", *sets, "--format", "csv,report", "--out", str(out), "-q"]) == 0
    )
    assert sorted(p.name for p in out.iterdir()) == [
        "report.html",
        "summary.json",
        "timeseries.csv",
    ]
    assert main(["run", "sensorless", *sets, "--format", "xls", "--out", str(out)]) == 2
    assert "no output format 'xls'" in capsys.readouterr().err


def test_to_xarray_with_the_formats_extra(res):
    pytest.importorskip("xarray", reason="the formats (and test) extra installs xarray")
    ds = res.to_xarray()
    assert ds["speed_rpm"].attrs["units"] == "rpm"
    assert ds.sizes["time_s"] == len(res.time_s)
