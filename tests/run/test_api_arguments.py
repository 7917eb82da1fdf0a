"""The Python API refuses a request it cannot meet with a ConfigError naming the argument,
never a raw TypeError / KeyError / OverflowError nor a silent NaN (issue 40, class 14)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imdrive.config.profiles import Profile
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.run.batch import simulate_batch
from imdrive.run.compare import compare
from imdrive.run.metrics import compensation_metrics
from imdrive.run.simulate import simulate

T_END = 0.05


@pytest.fixture(scope="module")
def sc():
    return Scenario.read("sensorless", [f"simulation.t_end_s={T_END}"])


@pytest.fixture(scope="module")
def res(sc):
    return simulate(sc)


CALLS = {
    "mean past the end": (lambda r: r.mean("speed_rpm", 5, 6), "t0"),
    "metrics window -1": (lambda r: r.metrics(window_s=-1), "window_s"),
    "metrics window nan": (lambda r: r.metrics(window_s=math.nan), "window_s"),
    "metrics window inf": (lambda r: r.metrics(window_s=math.inf), "window_s"),
    "metrics window text": (lambda r: r.metrics(window_s="0.1"), "window_s"),
    "compensation window -1": (lambda r: compensation_metrics(r, window_s=-1), "window_s"),
    "window(None)": (lambda r: r.window(None), "t0"),
    "window t1 nan": (lambda r: r.window(0.0, math.nan), "t1"),
    "window t1 < t0": (lambda r: r.window(0.02, 0.01), "t1"),
    "mean of no column": (lambda r: r.mean("nosuch", 0), "name"),
    "mean of None": (lambda r: r.mean(None, 0), "name"),
    "compare labels short": (lambda r: compare([r, r], labels=["a"]), "labels"),
    "Profile.constant(nan)": (lambda r: Profile.constant(math.nan), "value"),
    "Profile.constant(None)": (lambda r: Profile.constant(None), "value"),
    "Profile.scaled(inf)": (lambda r: Profile.constant(1.0).scaled(math.inf), "k"),
}


@pytest.mark.parametrize("call, field", CALLS.values(), ids=CALLS.keys())
def test_misuse_raises_config_error_naming_the_argument(res, call, field):
    with pytest.raises(ConfigError) as exc:
        call(res)
    assert exc.value.field == field
    assert "\n" not in str(exc.value)


def test_good_windows_still_answer(res):
    t = res.time_s
    inside = (t >= 0.01) & (t <= 0.02)
    assert res.mean("speed_rpm", 0.01, 0.02) == pytest.approx(np.mean(res["speed_rpm"][inside]))
    assert len(res.window(0.01)["time_s"]) == np.count_nonzero(t >= 0.01)
    assert math.isfinite(res.metrics(window_s=0.0)["speed_error_rpm"])


def test_a_window_longer_than_the_run_is_the_whole_run():
    """As documented (run/metrics.py): a window of 1e300 s is the whole run, not an overflow,
    in the batch engine as in ``res.metrics``; a ramp makes the window matter."""
    sc = Scenario.read(
        "sensorless",
        [
            "simulation.t_end_s=0.3",
            "control.speed_ref_rpm={initial=0, changes=[{at=0.0, to=600, over=0.2}]}",
            "control.premagnetise_T2=0",  # the ramp from t = 0, as written: the run is 0.3 s
        ],
    )
    cols = ["speed_error_rpm", "speed_ripple_rpm", "torque_mean_Nm"]
    whole = simulate_batch([sc], window_s=0.3).metrics[cols].to_numpy()
    huge = simulate_batch([sc], window_s=1e300).metrics[cols].to_numpy()
    short = simulate_batch([sc], window_s=0.05).metrics[cols].to_numpy()
    assert not np.allclose(short, whole)  # the window matters here
    np.testing.assert_array_equal(huge, whole)
    res = simulate(sc)
    m_whole, m_huge = res.metrics(window_s=0.3), res.metrics(window_s=1e300)
    assert [m_huge[c] for c in cols] == [m_whole[c] for c in cols]


def _plate():
    from imdrive.analysis.nameplate import Nameplate

    return Nameplate(2200, 400, 50, 4, 1436, 5.0, 0.79, 0.82)


def _more_calls():
    from imdrive.analysis.circuit_from_tests import circuit_from_tests
    from imdrive.analysis.foc import foc_operating_point
    from imdrive.analysis.nameplate import estimate_circuit
    from imdrive.config.machine import machine_preset

    m = machine_preset("paper-table-iv")
    return {
        "foc speed nan": (lambda r: foc_operating_point(m, math.nan, 0.0), "speed_rpm"),
        "foc load None": (lambda r: foc_operating_point(m, 600.0, None), "load_Nm"),
        "foc machine None": (lambda r: foc_operating_point(None, 600.0, 0.0), "machine"),
        "estimate_circuit(None)": (lambda r: estimate_circuit(None), "plate"),
        "estimate_circuit lee bogus": (
            lambda r: estimate_circuit(_plate(), method="lee", bogus=1),
            "bogus",
        ),
        "circuit_from_tests(None...)": (lambda r: circuit_from_tests(None, None, None), "no_load"),
        "from_toml base_dir=5": (
            lambda r: Scenario.from_toml('name = "x"', base_dir=5),
            "base_dir",
        ),
        "save(None)": (lambda r: r.save(None), "out_dir"),
        "to_csv('.')": (lambda r: r.to_csv("."), "path"),
        "to_csv(None)": (lambda r: r.to_csv(None), "path"),
    }


@pytest.mark.parametrize("name", list(_more_calls()))
def test_more_misuse_raises_config_error_naming_the_argument(res, name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    call, field = _more_calls()[name]
    with pytest.raises(ConfigError) as exc:
        call(res)
    assert exc.value.field == field
    assert list(tmp_path.iterdir()) == []


def test_to_csv_still_writes_a_file_and_through_a_link(res, tmp_path):
    target = tmp_path / "data.csv"
    target.write_text("old")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    res.to_csv(link)
    assert link.is_symlink()
    assert target.read_text().splitlines()[0] == ",".join(res.columns)


def _deep_list(n: int = 5000) -> list:
    top: list = []
    node = top
    for _ in range(n):
        node.append([])
        node = node[0]
    return top


@pytest.mark.parametrize("where", ["description", "control.current_kp", "plugins.modules"], ids=str)
def test_a_value_nested_5000_deep_is_a_config_error(where):
    *head, key = where.split(".")
    data: dict = {}
    node = data
    for part in head:
        node = node.setdefault(part, {})
    node[key] = _deep_list()
    with pytest.raises(ConfigError) as exc:
        Scenario.from_dict(data)
    assert exc.value.field.startswith(where) and len(str(exc.value)) < 200
