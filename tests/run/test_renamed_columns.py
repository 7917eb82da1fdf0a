"""Renamed columns and metrics: the new names are exported, the old ones still answer with a
DeprecationWarning for one release (docs/outputs.md, "Renamed columns")."""

import warnings

import numpy as np
import pytest

from imdrive.bench.metrics import run_metrics
from imdrive.config.scenario import Scenario
from imdrive.run.columns import (
    OPEN_LOOP_COLUMNS,
    RENAMED_COLUMNS,
    RENAMED_METRICS,
    VECTOR_COLUMNS,
    Columns,
)
from imdrive.run.simulate import simulate


@pytest.fixture(scope="module")
def res():
    return simulate(
        Scenario.read("injection-fig5", ["simulation.t_end_s=0.3", "compensator.t_on_s=0.1"])
    )


def test_the_new_names_are_the_exported_columns():
    for old, new in RENAMED_COLUMNS.items():
        assert new in VECTOR_COLUMNS and old not in VECTOR_COLUMNS + OPEN_LOOP_COLUMNS
        assert new.startswith(old.split("_est_")[0] + "_hat_")


def test_result_exports_carry_only_the_new_names(res, tmp_path):
    assert "R2_hat_ohm" in res.columns and "R1_hat_ohm" in res.columns
    assert not set(RENAMED_COLUMNS) & set(res.columns)
    assert not set(RENAMED_COLUMNS) & set(res.to_pandas().columns)
    res.to_csv(tmp_path / "r.csv")
    header = (tmp_path / "r.csv").read_text().splitlines()[0]
    assert "R2_hat_ohm" in header and "R2_est_ohm" not in header


def test_old_column_name_answers_with_a_warning(res):
    new = res.signals["R2_hat_ohm"]
    with pytest.warns(DeprecationWarning, match="'R2_est_ohm' is renamed 'R2_hat_ohm'"):
        assert res["R2_est_ohm"] is new
    with pytest.warns(DeprecationWarning):
        assert res.signals["R1_est_ohm"] is res.signals["R1_hat_ohm"]
    with pytest.warns(DeprecationWarning):
        assert "R2_est_ohm" in res.signals
    with pytest.warns(DeprecationWarning):
        assert res.signals.get("R2_est_ohm") is new
    with pytest.warns(DeprecationWarning):
        w = res.window(0.2)["R2_est_ohm"]
    np.testing.assert_array_equal(w, new[res.time_s >= 0.2])
    with pytest.warns(DeprecationWarning):
        assert res.mean("R2_est_ohm", 0.2) == float(np.mean(w))


def test_the_warning_points_at_the_callers_line(res):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res["R2_est_ohm"]
        res.signals["R2_est_ohm"]
        res.signals.get("R2_est_ohm")
        "R2_est_ohm" in res.signals  # noqa: B015
    assert len(caught) == 4
    assert {w.filename for w in caught} == {__file__}


def test_new_names_and_unknown_names_do_not_warn(res):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert res.signals.get("R2_hat_ohm") is res["R2_hat_ohm"]
        assert "no_such_column" not in res.signals
        assert res.signals.get("no_such_column", 7) == 7
        with pytest.raises(KeyError):
            res["no_such_column"]
    assert Columns({"a": 1}) == {"a": 1}


def test_plot_accepts_an_old_name(res):
    import matplotlib.pyplot as plt

    with pytest.warns(DeprecationWarning):
        fig = res.plot(["R2_est_ohm"])
    plt.close(fig)


def test_compensation_metrics_old_keys(res):
    m = res.compensation_metrics()
    assert not set(RENAMED_METRICS) & set(m)
    assert m["R2_hat_initial_ohm"] == res["R2_hat_ohm"][0]
    for old, new in RENAMED_METRICS.items():
        with pytest.warns(DeprecationWarning):
            assert m[old] == m[new]
    assert res.summary()["compensation"]["R2_hat_final_ohm"] == res["R2_hat_ohm"][-1]


def test_bench_metrics_take_a_mapping_with_the_old_name():
    t = np.linspace(0.0, 1.0, 101)
    sig = {
        "time_s": t,
        "speed_rpm": np.full_like(t, 100.0),
        "speed_ref_rpm": np.full_like(t, 100.0),
        "speed_est_rpm": np.full_like(t, 100.0),
        "R2_ohm": np.ones_like(t),
        "i_alpha_A": np.ones_like(t),
        "i_beta_A": np.zeros_like(t),
    }
    want = run_metrics({**sig, "R2_hat_ohm": 1.1 * np.ones_like(t)}, 0.5, False)
    with pytest.warns(DeprecationWarning):
        got = run_metrics({**sig, "R2_est_ohm": 1.1 * np.ones_like(t)}, 0.5, False)
    assert got == pytest.approx(want, nan_ok=True)


def test_every_rename_is_in_the_changelog():
    """Issue 39: ``R2_est_ohm`` became ``R2_hat_ohm`` with no changelog entry. Each renamed
    column and metric is named, old and new, in CHANGELOG.md."""
    from pathlib import Path

    changelog = (Path(__file__).resolve().parents[2] / "CHANGELOG.md").read_text("utf-8")
    for old, new in RENAMED_COLUMNS.items():
        assert f"`{old}`" in changelog and f"`{new}`" in changelog, old
    for old in RENAMED_METRICS:
        assert f"`{old}`" in changelog, old


def test_an_old_csv_reader_gets_the_old_names_back_as_documented(res, tmp_path):
    """docs/outputs.md's recipe for a script that reads timeseries.csv by the old names."""
    import pandas as pd

    res.to_csv(tmp_path / "r.csv")
    old_names = {new: old for old, new in RENAMED_COLUMNS.items()}
    df = pd.read_csv(tmp_path / "r.csv").rename(columns=old_names)
    np.testing.assert_allclose(df["R2_est_ohm"], res.signals["R2_hat_ohm"], rtol=1e-9)
