"""The settings schema (``imdrive.config``): one source for validation, overrides and docs.

Error messages for each kind of broken rule, ConfigError from direct construction and from
``dataclasses.replace``, round trips of every preset, the generated ``docs/scenarios.md`` and
the JSON Schema, and the layer rule (config never imports numba, the kernels or the runner).
"""

from __future__ import annotations

import ast
import dataclasses
import json
import os
import subprocess
import sys
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import imdrive.config
from imdrive.config import docs
from imdrive.config.estimators import ESTIMATOR_SETTINGS
from imdrive.config.inverter import InverterParams
from imdrive.config.machine import MachineParams, machine_preset
from imdrive.config.overrides import is_setting
from imdrive.config.presets import preset_names, preset_text
from imdrive.config.profiles import Profile
from imdrive.config.scenario import (
    SECTIONS,
    CompensatorSettings,
    ControlSettings,
    PlantSettings,
    Scenario,
    SimulationSettings,
    ThermalSettings,
)
from imdrive.config.schema import scenario_keys
from imdrive.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]
CONFIG_DIR = Path(imdrive.config.__file__).parent


def _error(fn) -> str:
    with pytest.raises(ConfigError) as exc:
        fn()
    return str(exc.value)


# ------------------------------------------------------------------------------------------
# error messages: one line, the field's path, today's wording

FROM_DICT = [
    # (scenario dictionary, the whole message)
    ({"machine": {"R1_ohm": -1}}, "machine.R1_ohm: must be > 0 (got -1.0)"),
    ({"simulation": {"Ts_s": 0}}, "simulation.Ts_s: must be > 0 (got 0.0)"),
    (
        {"plant": {"thermal": {"alpha1_per_K": -0.5}}},
        "plant.thermal.alpha1_per_K: must be >= 0 (got -0.5)",
    ),
    ({"simulation": {"substeps": 0}}, "simulation.substeps: must be >= 1 (got 0)"),
    ({"drive": {"mode": "sideways"}}, "drive.mode: must be one of 'open-loop', 'vector'"),
    ({"inverter": {"model": "svpwm"}}, "inverter.model: must be one of 'average', 'switching'"),
    ({"simulation": {"substepz": 2}}, "simulation.substepz: unknown key"),
    ({"plant": {"thermal": {"tau3_s": 2}}}, "plant.thermal.tau3_s: unknown key"),
    ({"machine": {"R3_ohm": 1.0}}, "machine.R3_ohm: unknown key"),
    ({"foo": 1}, "foo: unknown key"),
    ({"machine_preset": "krause-3hp"}, "machine_preset: unknown key"),
    ({"output": {"figures": 1}}, "output.figures: must be true or false, got 1"),
    ({"simulation": {"substeps": 1.5}}, "simulation.substeps: must be an integer, got 1.5"),
    ({"simulation": {"substeps": True}}, "simulation.substeps: must be an integer, got True"),
    ({"simulation": {"log_every": "7"}}, "simulation.log_every: must be an integer, got '7'"),
    ({"machine": {"J_kgm2": True}}, "machine.J_kgm2: must be a number, got True"),
    ({"simulation": {"t_end_s": "fast"}}, "simulation.t_end_s: must be a number, got 'fast'"),
    ({"simulation": {"t_end_s": float("nan")}}, "simulation.t_end_s: must be finite"),
    ({"control": {"speed_kp": float("inf")}}, "control.speed_kp: must be finite"),
    ({"name": 3}, "name: must be a string, got 3"),
    ({"load": 5}, "load: must be a table"),
    ({"machine": 5}, "machine: must be a table"),
    ({"machine": {"preset": 3}}, "machine.preset: must be a string, got 3"),
    # rules inside validators keep their own path below the field
    ({"load": {"torque_Nm": float("nan")}}, "load.torque_Nm: must be finite"),
    (
        {"control": {"speed_ref_rpm": {"points": [[1, 0], [0, 1]]}}},
        "control.speed_ref_rpm.points[1]: times must be non-decreasing",
    ),
    (
        {"plant": {"R2_scale": {"initial": 1, "changes": [{"at": 1}]}}},
        "plant.R2_scale.changes[0]: needs 'at' and 'to'",
    ),
    ({"plant": {"R2_scale": {"points": [[0, 1], [1, 0]]}}}, "plant.R2_scale: must be > 0"),
    ({"control": {"flux_ref_Wb": 0}}, "control.flux_ref_Wb: must be > 0"),
    ({"open_loop": {"voltage_V": -1}}, "open_loop.voltage_V: must be >= 0"),
    # cross-field rules
    (
        {"simulation": {"t_end_s": 1e-3, "Ts_s": 1e-2}},
        "simulation.Ts_s: must be <= simulation.t_end_s",
    ),
    (
        {"compensator": {"R2_min_ohm": 1.0, "R2_max_ohm": 0.5}},
        "compensator.R2_min_ohm: must be < compensator.R2_max_ohm",
    ),
    (
        {"open_loop": {"vf_ramp_s": 1.0, "voltage_V": {"points": [[0, 0], [1, 220]]}}},
        "open_loop.vf_ramp_s: needs constant voltage_V and frequency_Hz (the ramp ends at them)",
    ),
]


@pytest.mark.parametrize(("data", "message"), FROM_DICT, ids=[m for _, m in FROM_DICT])
def test_from_dict_error_messages(data, message):
    assert _error(lambda: Scenario.from_dict(data)) == message


def test_unknown_machine_preset():
    msg = _error(lambda: Scenario.from_dict({"machine": {"preset": "no-such"}}))
    assert msg.startswith("machine.preset: unknown preset 'no-such'; known: [")


def test_only_the_first_error_one_line():
    msg = _error(lambda: Scenario.from_dict({"simulation": {"Ts_s": -1, "substeps": 0}}))
    assert msg == "simulation.Ts_s: must be > 0 (got -1.0)"
    assert "\n" not in msg


# ------------------------------------------------------------------------------------------
# direct construction and replace: the same rules, the section prefix

M = {"R1_ohm": 0.435, "R2_ohm": 0.816, "Ll1_H": 0.002, "Ll2_H": 0.002, "M_H": 0.0693}

# the package's first four in this order, then every further registered estimator (each adds
# its settings class, config/estimators.py) in registration order
_FIRST = ("measured", "mras", "reactive-mras", "afo", "ekf")
_KNOWN_ESTIMATORS = [*_FIRST, *(n for n in ESTIMATOR_SETTINGS if n not in _FIRST)]

DIRECT = [
    (lambda: MachineParams(**(M | {"R1_ohm": -1})), "machine.R1_ohm: must be > 0 (got -1.0)"),
    (lambda: MachineParams(**(M | {"pole_pairs": 0})), "machine.pole_pairs: must be >= 1 (got 0)"),
    (lambda: MachineParams(0.435, 0.816, 0.002, 0.002), "machine.M_H: is required"),
    (lambda: MachineParams(**M, bogus=1), "machine.bogus: unknown key"),
    (
        lambda: ControlSettings(speed_feedback="x"),
        "control.speed_feedback: must be one of " + ", ".join(map(repr, _KNOWN_ESTIMATORS)),
    ),
    (lambda: ThermalSettings(tau1_s=0), "plant.thermal.tau1_s: must be > 0 (got 0.0)"),
    (lambda: SimulationSettings(substeps="a"), "simulation.substeps: must be an integer, got 'a'"),
    (lambda: SimulationSettings(Ts_s=2.0), "simulation.Ts_s: must be <= simulation.t_end_s"),
    (
        lambda: CompensatorSettings(R2_min_ohm=2.0, R2_max_ohm=1.0),
        "compensator.R2_min_ohm: must be < compensator.R2_max_ohm",
    ),
    (lambda: PlantSettings(R1_scale=Profile.constant(-1.0)), "plant.R1_scale: must be > 0"),
    (lambda: InverterParams(Vdc_V=float("nan")), "inverter.Vdc_V: must be finite"),
    (lambda: Scenario(simulation=5), "simulation: must be a table"),
    (lambda: machine_preset("no-such").R1_ohm, None),
]


@pytest.mark.parametrize(("build", "message"), DIRECT, ids=[str(m) for _, m in DIRECT])
def test_direct_construction_raises_config_error(build, message):
    msg = _error(build)
    if message is not None:
        assert msg == message


def test_replace_validates_again():
    sc = Scenario.read("sensorless")
    assert _error(lambda: replace(sc.simulation, log_every=0)) == (
        "simulation.log_every: must be >= 1 (got 0)"
    )
    assert _error(lambda: replace(sc.machine, R2_ohm=-0.8)) == (
        "machine.R2_ohm: must be > 0 (got -0.8)"
    )
    assert _error(lambda: sc.with_(drive=replace(sc.drive, mode="x"))).startswith("drive.mode:")
    assert _error(lambda: replace(sc, name=None)) == "name: must be a string, got None"
    # and a valid change equals the same change made in the file
    sc7 = replace(sc, simulation=replace(sc.simulation, log_every=7))
    assert sc7 == Scenario.read("sensorless", ["simulation.log_every=7"])
    assert sc7.simulation.log_every == 7 and sc.simulation.log_every == 10


def test_settings_stay_stdlib_dataclasses():
    sc = Scenario.read("injection-fig5")
    assert dataclasses.is_dataclass(sc) and dataclasses.is_dataclass(sc.compensator)
    names = [f.name for f in dataclasses.fields(Scenario)]
    assert names[:4] == ["name", "description", "machine", "machine_preset"]
    assert set(SECTIONS) <= set(names)
    # defaults are plain values (not pydantic FieldInfo) and the objects are frozen, hashable
    assert {f.name: f.default for f in dataclasses.fields(SimulationSettings)}["Ts_s"] == 100e-6
    with pytest.raises(dataclasses.FrozenInstanceError):
        sc.simulation.Ts_s = 1.0
    assert hash(sc) == hash(Scenario.read("injection-fig5"))


def test_numbers_accepted_as_today():
    # an int where a float is expected is stored as a float; 2.0 is an integer
    assert SimulationSettings(t_end_s=2).t_end_s == 2.0
    assert type(SimulationSettings(t_end_s=2).t_end_s) is float
    assert type(SimulationSettings(substeps=2.0).substeps) is int
    # numpy scalars are the numbers they hold
    m = MachineParams(**(M | {"R1_ohm": np.float32(0.5), "pole_pairs": np.int64(3)}))
    assert type(m.R1_ohm) is float and type(m.pole_pairs) is int and m.pole_pairs == 3
    # a profile field takes the file forms too
    assert ControlSettings(speed_ref_rpm=1000).speed_ref_rpm == Profile.constant(1000.0)


# ------------------------------------------------------------------------------------------
# round trips


@pytest.mark.parametrize("name", preset_names())
def test_preset_round_trip(name):
    sc = Scenario.read(name)
    assert Scenario.from_dict(sc.to_dict()) == sc
    # through JSON too (summary.json): None for an unset optional, lists for points
    assert Scenario.from_dict(json.loads(json.dumps(sc.to_dict()))) == sc


def _toml(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return json.dumps(value)  # strings, numbers, lists of points


def test_every_key_is_a_setting_and_takes_its_default():
    """Each key of the schema can be set with --set to its current value, changing nothing."""
    base = Scenario.read("free-acceleration")
    plain = base.to_dict()
    for key in scenario_keys():
        if key.table is not None and len(key.path) == 1:
            assert not is_setting(key.path), key.dotted  # a whole section is not one value
            continue
        assert is_setting(key.path), key.dotted
        value = plain
        for p in key.path:
            value = value.get(p)  # machine.description is not written back
        if value is None or isinstance(value, dict):
            continue  # None has no TOML form; a table's keys are checked one by one
        assert Scenario.read("free-acceleration", [f"{key.dotted}={_toml(value)}"]) == base


# ------------------------------------------------------------------------------------------
# docs/scenarios.md and the JSON Schema


def test_scenarios_md_is_generated_from_the_schema():
    committed = (ROOT / "docs" / "scenarios.md").read_text(encoding="utf-8")
    assert committed == docs.markdown(), (
        "docs/scenarios.md is stale: run 'PYTHONPATH=src python -m imdrive.config.docs'"
    )


def test_scenarios_md_names_every_key():
    from imdrive.config.deprecated_keys import is_listed_apart

    text = docs.markdown()
    for key in scenario_keys():
        if key.table is not None:
            assert f"### `[{key.dotted}]`" in text
        elif is_listed_apart(key.path):  # a deprecated twin: in the section of its own
            assert f"| `{key.dotted}` |" in text.split("## Deprecated keys")[1], key.dotted
        else:
            assert f"| `{key.path[-1]}` |" in text, key.dotted
            assert key.info.description, f"{key.dotted} has no description"


def test_docs_check_command(tmp_path):
    path = tmp_path / "scenarios.md"
    path.write_text("old\n")
    assert docs.main(["--check", "--path", str(path)]) == 1
    assert docs.main(["--path", str(path)]) == 0
    assert docs.main(["--check", "--path", str(path)]) == 0


def test_json_schema_names_every_section():
    schema = docs.json_schema()
    props = schema["properties"]
    assert set(SECTIONS) | {"name", "description", "machine"} == set(props)
    assert schema["additionalProperties"] is False
    machine = schema["$defs"]["MachineParams"]
    assert "required" not in machine and "preset" in machine["properties"]
    ctl = schema["$defs"]["ControlSettings"]["properties"]
    assert ctl["speed_ref_rpm"]["default"] == 0.0 and ctl["speed_ref_rpm"]["unit"] == "rpm"
    json.dumps(schema)  # serialisable as is


@pytest.fixture(scope="module")
def schema_validator():
    """The scenario's JSON schema, checked against the 2020-12 metaschema, as a validator:
    built once for every preset (0.5-1.5 s on 2 cores, 20 times when each test built it)."""
    jsonschema = pytest.importorskip("jsonschema")
    schema = docs.json_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


@pytest.mark.parametrize("name", preset_names())
def test_every_preset_validates_against_the_json_schema(name, schema_validator):
    validator = schema_validator
    data = tomllib.loads(preset_text(name))
    assert not list(validator.iter_errors(data))
    # and the schema does reject what the loader rejects
    bad = data | {"simulation": {"substepz": 2}}
    assert list(validator.iter_errors(bad))


# ------------------------------------------------------------------------------------------
# layers


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
    return names


@pytest.mark.parametrize("path", sorted(CONFIG_DIR.glob("*.py")), ids=lambda p: p.name)
def test_config_imports_no_numba_kernels_or_runner(path):
    for name in _imports(path):
        assert not name.startswith(("numba", "imdrive.kernels", "imdrive.run")), (path, name)
        if name.startswith("imdrive."):
            # the gain formulas (design, numba-free) serve the estimators' settings classes
            allowed = ("imdrive.config", "imdrive.errors", "imdrive.design")
            assert name.startswith(allowed), (path, name)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_config_import_loads_no_numba():
    code = (
        "import sys, imdrive.config.docs, imdrive.config.overrides, imdrive.config.presets; "
        "bad = [m for m in sys.modules if m.split('.')[0] == 'numba' "
        "or m.startswith(('imdrive.kernels', 'imdrive.run'))]; "
        "assert not bad, bad"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
