"""Property-based tests over the public API's arguments (issue 40, "must show"): hypothesis
draws hostile arguments (None, booleans, NaN, infinities, 1e308, subnormals, empty and long
strings, lists, tables, objects, bytes, hostile paths) for every public entry point; each
answers with a value (a NaN float counts as a failure) or a one-line ConfigError, never a raw
error, a silent NaN or a hang. Bounded for CI: a few examples per function, no deadline.
"""

from __future__ import annotations

import math

import pytest
from data.hostile import bounded_property, call_api, make_path

hypothesis = pytest.importorskip("hypothesis")
st = pytest.importorskip("hypothesis.strategies")

POOL = (
    None, True, False, 0, -1, 1, 2**70, 0.0, -0.0, 1e-320, 1e308, -1e308, math.nan, math.inf,
    -math.inf, "", " ", "x", "a" * 300, "sensorless", "nosuch", "1e308", "nan", "\0", b"bytes",
    [], [1, "a"], [[[]]], {}, {"a": 1}, {"machine": "x"}, (1, 2), object(), 1 + 2j,
)  # fmt: skip
PATH_KINDS = ("fifo", "socket", "device", "dangling", "too-long", "folder", "under-a-file",
              "loop", "file")  # fmt: skip
EXAMPLES = 15


@pytest.fixture(scope="module")
def res():
    from imdrive import Scenario, simulate

    return simulate(Scenario.read("sensorless", ["simulation.t_end_s=0.02"]))


@st.composite
def _arg(draw, tmp):
    if draw(st.integers(0, 3)) == 0:
        return make_path(tmp, draw(st.sampled_from(PATH_KINDS)),
                         draw(st.sampled_from(("", ".toml", ".json", ".csv"))))  # fmt: skip
    return draw(st.sampled_from(POOL))


def _functions(res):
    """name -> (function, number of hostile positional arguments)."""
    from imdrive import Profile, Scenario, machine_preset, replay, simulate, simulate_batch
    from imdrive.analysis.circuit_from_tests import circuit_from_tests
    from imdrive.analysis.foc import foc_operating_point
    from imdrive.analysis.nameplate import estimate_circuit
    from imdrive.commission import commission
    from imdrive.run.compare import compare
    from imdrive.sweep import load_sweep, parse_sweep, run_sweep

    m = res.scenario.machine
    return {
        "Scenario.read": (Scenario.read, 1),
        "Scenario.read+overrides": (lambda a, b: Scenario.read("sensorless", [a, b]), 2),
        "Scenario.from_toml": (lambda a, b: Scenario.from_toml(a, base_dir=b), 2),
        "Scenario.from_dict": (Scenario.from_dict, 1),
        "simulate": (simulate, 1),
        "simulate_batch": (lambda a, b: simulate_batch([a], window_s=b), 2),
        "Profile.constant": (Profile.constant, 1),
        "Profile.scaled": (lambda a: Profile.constant(1.0).scaled(a), 1),
        "machine_preset": (machine_preset, 1),
        "replay": (lambda a, b, c: replay(a, b, c, None), 3),
        "compare": (lambda a, b: compare([res, a], labels=b), 2),
        "foc_operating_point": (lambda a, b: foc_operating_point(m, a, b), 2),
        "estimate_circuit": (estimate_circuit, 1),
        "circuit_from_tests": (circuit_from_tests, 3),
        "commission": (commission, 1),
        "load_sweep": (load_sweep, 1),
        "parse_sweep": (parse_sweep, 1),
        "run_sweep": (lambda a, b: run_sweep(a, b), 2),
        "res.mean": (lambda a, b, c: res.mean(a, b, c), 3),
        "res.window": (lambda a, b: res.window(a, b), 2),
        "res.metrics": (lambda a: res.metrics(window_s=a), 1),
        "res.save": (lambda a: res.save(a), 1),
        "res.to_csv": (lambda a: res.to_csv(a), 1),
    }


NAMES = sorted((
    "Scenario.read", "Scenario.read+overrides", "Scenario.from_toml", "Scenario.from_dict",
    "simulate", "simulate_batch", "Profile.constant", "Profile.scaled", "machine_preset",
    "replay", "compare", "foc_operating_point", "estimate_circuit", "circuit_from_tests",
    "commission", "load_sweep", "parse_sweep", "run_sweep", "res.mean", "res.window",
    "res.metrics", "res.save", "res.to_csv",
))  # fmt: skip


def test_the_list_names_every_function(res):
    assert set(_functions(res)) == set(NAMES)


@pytest.mark.parametrize("name", NAMES)
def test_hostile_arguments_give_a_value_or_a_config_error(res, tmp_path_factory, monkeypatch, name):
    fn, n = _functions(res)[name]
    # a relative name that is a valid folder (res.save("x")) is written here, not in the
    # repository the tests run from
    monkeypatch.chdir(tmp_path_factory.mktemp("cwd"))

    @bounded_property(EXAMPLES)
    @hypothesis.given(data=st.data())
    def check(data):
        tmp = tmp_path_factory.mktemp("api")
        args = [data.draw(_arg(tmp)) for _ in range(n)]
        outcome, detail = call_api(fn, *args, bound_s=60.0)
        assert outcome != "failure", (name, args, detail)

    check()
