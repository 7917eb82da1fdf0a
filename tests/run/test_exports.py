"""Exports (MAT, Parquet, xarray), the Python API's conveniences and the output reference."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.io import loadmat

import imdrive as im
from imdrive.errors import ConfigError
from imdrive.run import outputs
from imdrive.run.export import read_parquet_units, unit_of

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def res():
    sc = im.Scenario.read("sensorless").with_overrides(
        ["simulation.t_end_s=0.3", "output.figures=false"]
    )
    return im.simulate(sc)


def test_mat_round_trip_every_column_with_units(res, tmp_path):
    from imdrive.run.export import to_mat

    to_mat(res, tmp_path / "t.mat")
    d = loadmat(tmp_path / "t.mat", squeeze_me=True)
    units = d["units"]
    for name, v in res.signals.items():
        assert np.array_equal(np.asarray(d[name]).reshape(-1), v), name
        assert str(units[name]) == unit_of(name)


def test_parquet_round_trip_every_column_with_units(res, tmp_path):
    import pandas as pd

    from imdrive.run.export import to_parquet

    to_parquet(res, tmp_path / "t.parquet")
    df = pd.read_parquet(tmp_path / "t.parquet")
    assert list(df.columns) == res.columns
    for name, v in res.signals.items():
        assert np.array_equal(df[name].to_numpy(), v), name
    assert read_parquet_units(tmp_path / "t.parquet")["speed_rpm"] == "rpm"


def test_output_settings_write_the_exports(tmp_path):
    sc = im.Scenario.read("vector-sensored").with_overrides(
        [
            "simulation.t_end_s=0.05",
            "output.figures=false",
            "output.mat=true",
            "output.parquet=true",
        ]
    )
    written = {p.name for p in im.simulate(sc).save(tmp_path / "out")}
    assert {"timeseries.mat", "timeseries.parquet", "summary.json"} <= written


def test_to_xarray_has_units_or_says_how_to_get_it(res):
    try:
        import xarray  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError, match="pip install xarray"):
            res.to_xarray()
        return
    ds = res.to_xarray()
    assert ds["speed_rpm"].attrs["units"] == "rpm"


def test_top_level_api_and_plot(res):
    fig = res.plot()
    assert len(fig.axes) == 5
    fig = res.plot(signals=["speed_rpm", "e_d0_Wb"])
    assert len(fig.axes) == 2
    with pytest.raises(KeyError, match="no such column"):
        res.plot(signals=["speed"])


def test_with_overrides_validates_and_refuses_a_string():
    sc = im.Scenario.read("sensorless")
    assert sc.with_overrides({"estimator.R2_ohm": 0.9}).estimator.R2_ohm == 0.9
    with pytest.raises(ConfigError, match="list of"):
        sc.with_overrides("estimator.R2_ohm=0.9")
    with pytest.raises(ConfigError) as exc:
        sc.with_overrides(["estimator.R2_ohm=-1"])
    assert exc.value.field == "estimator.R2_ohm"


def test_output_reference_is_current_and_covers_every_column(res):
    text = (ROOT / "docs" / "outputs.md").read_text()
    assert text == outputs.markdown(), "run python -m imdrive.run.outputs"
    for name in res.columns:
        assert f"`{name}`" in text and name in outputs.COLUMN_DOCS


def _links(md: str):
    for m in re.finditer(r"\]\(([^)\s]+)\)", md):
        target = m.group(1)
        if not target.startswith(("http://", "https://", "mailto:", "#")):
            yield target


@pytest.mark.parametrize(
    "doc",
    sorted(str(p.relative_to(ROOT)) for p in [ROOT / "README.md", *(ROOT / "docs").glob("*.md")]),
)
def test_every_relative_link_resolves_inside_the_repository(doc):
    path = ROOT / doc
    for target in _links(path.read_text()):
        file = (path.parent / target.split("#")[0]).resolve()
        assert file.is_relative_to(ROOT), f"{doc}: {target} leaves the repository"
        assert file.exists(), f"{doc}: {target} does not exist"
