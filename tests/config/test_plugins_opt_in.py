"""Plug-ins are opt-in (issue 40, class 1): a module a received file names in
``[plugins] modules`` is imported only when the user allows it for this invocation
(``--allow-plugins``, ``IMDRIVE_ALLOW_PLUGINS=1``, ``allow_plugins=True``); looking at a file
(``show``, ``show --all``, ``sweep --dry-run``, ``compare``) never imports one. Each module
here writes a marker file when it runs, so "no code ran" is checked, not assumed."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest

from imdrive import Scenario
from imdrive.cli import build_parser, main
from imdrive.config.plugins import ALLOW_ENV, allowing_plugins, module_hashes
from imdrive.errors import ConfigError, ConfigWarning
from imdrive.sweep import load_sweep

OWN = Path(__file__).parents[1] / "data" / "own_estimator.py"


@pytest.fixture(autouse=True)
def _no_env_permission(monkeypatch):
    monkeypatch.delenv(ALLOW_ENV, raising=False)


def _module(folder: Path, name: str = "evil.py") -> tuple[Path, Path]:
    """A module that leaves a marker beside itself when imported: (module, marker)."""
    folder.mkdir(parents=True, exist_ok=True)
    mod = folder / name
    marker = folder / (name + ".RAN")
    mod.write_text(f"import pathlib\npathlib.Path({str(marker)!r}).write_text('ran')\n")
    return mod, marker


def _scenario_file(folder: Path, modules, extra: str = "") -> Path:
    f = folder / "sc.toml"
    f.write_text(
        f'name = "sc"\n[plugins]\nmodules = {json.dumps(modules)}\n'
        "[simulation]\nt_end_s = 0.02\n" + extra
    )
    return f


def _err(capsys) -> str:
    return capsys.readouterr().err


def test_a_scenario_file_naming_a_module_is_refused_and_runs_nothing(tmp_path):
    mod, marker = _module(tmp_path / "a")
    f = _scenario_file(tmp_path / "a", [str(mod)])
    with pytest.raises(ConfigError) as exc:
        Scenario.read(str(f))
    assert exc.value.field == "plugins.modules[0]"
    assert str(mod) in str(exc.value) and "--allow-plugins" in str(exc.value)
    assert not marker.exists()
    # a dotted module name is refused the same way, before anything is imported
    with pytest.raises(ConfigError, match=r"plugins\.modules\[0\].*'no_such_mod_xyz'"):
        Scenario.read("sensorless", ['plugins.modules=["no_such_mod_xyz"]'])


def test_every_api_reader_refuses_without_permission(tmp_path):
    mod, marker = _module(tmp_path)
    with pytest.raises(ConfigError, match=r"plugins\.modules\[0\]"):
        Scenario.from_toml(f'[plugins]\nmodules = ["{mod}"]\n')
    with pytest.raises(ConfigError, match=r"plugins\.modules\[0\]"):
        Scenario.from_dict({"plugins": {"modules": [str(mod)]}})
    with pytest.raises(ConfigError, match=r"plugins\.modules\[0\]"):
        Scenario.read("sensorless", [f'plugins.modules=["{mod}"]'])
    assert not marker.exists()


def test_a_summary_json_naming_a_module_is_refused(tmp_path):
    mod, marker = _module(tmp_path)
    data = Scenario.read("sensorless").to_dict()
    data["plugins"]["modules"] = [str(mod)]
    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps({"scenario": data}))
    with pytest.raises(ConfigError, match=r"plugins\.modules\[0\]"):
        Scenario.read(str(summary))
    assert not marker.exists()


def test_a_sweep_file_naming_a_module_is_refused(tmp_path):
    mod, marker = _module(tmp_path)
    f = tmp_path / "sw.toml"
    f.write_text(
        f'name = "s"\nbase = "sensorless"\n[set]\nplugins.modules = ["{mod.name}"]\n'
        "[axes]\nspeed_rpm = [800, 1200]\n"
    )
    with pytest.raises(ConfigError, match=r"plugins\.modules\[0\]"):
        load_sweep(str(f))
    assert not marker.exists()
    # allowed: the [set] path is read from the sweep file's folder, not the current one
    load_sweep(str(f), allow_plugins=True)
    assert marker.exists()


def test_allowed_by_the_api_flag_the_environment_or_a_block(tmp_path, monkeypatch):
    for how in ("flag", "env", "block"):
        mod, marker = _module(tmp_path / how)
        override = [f'plugins.modules=["{mod}"]']
        if how == "flag":
            Scenario.read("sensorless", override, allow_plugins=True)
        elif how == "env":
            monkeypatch.setenv(ALLOW_ENV, "1")
            Scenario.read("sensorless", override)
            monkeypatch.delenv(ALLOW_ENV)
        else:
            with allowing_plugins():
                Scenario.read("sensorless", override)
        assert marker.exists(), how


def test_a_relative_path_is_read_from_the_scenario_files_folder(tmp_path, monkeypatch):
    mod, marker = _module(tmp_path / "project")
    f = _scenario_file(tmp_path / "project", [mod.name])
    elsewhere = tmp_path / "elsewhere"
    _module(elsewhere)  # the same name in the current folder must not be the one imported
    monkeypatch.chdir(elsewhere)
    sc = Scenario.read(str(f), allow_plugins=True)
    assert marker.exists() and not (elsewhere / "evil.py.RAN").exists()
    assert sc.plugins.modules == (str(mod.resolve()),)


@pytest.mark.parametrize("extra", [[], ["--all"]])
def test_show_names_the_module_and_imports_nothing(tmp_path, capsys, monkeypatch, extra):
    mod, marker = _module(tmp_path)
    f = _scenario_file(tmp_path, [mod.name])
    monkeypatch.setenv(ALLOW_ENV, "1")  # even when allowed, looking does not import
    capsys.readouterr()
    assert main(["show", str(f), *extra]) == 0
    out = capsys.readouterr().out
    assert "not imported" in out and str(mod) in out
    assert not marker.exists()


def test_show_of_a_plug_in_estimators_scenario_lists_it_unchecked(tmp_path, capsys):
    f = _scenario_file(
        tmp_path,
        [str(OWN)],
        '[drive]\nmode = "vector"\n[control]\nspeed_feedback = "flux-angle"\n'
        "[plugins.settings.flux-angle]\nfilter_Hz = 10\n",
    )
    # a copy of the module under a new path: not imported in this process by other tests
    copy = tmp_path / "own_copy.py"
    copy.write_text(OWN.read_text())
    f.write_text(f.read_text().replace(str(OWN), str(copy)))
    capsys.readouterr()
    assert main(["show", str(f), "--all"]) == 0
    out = capsys.readouterr().out
    assert "speed feedback flux-angle" in out and str(copy) in out
    assert "filter_Hz = 10" in out


def test_sweep_dry_run_names_the_module_and_imports_nothing(tmp_path, capsys, monkeypatch):
    mod, marker = _module(tmp_path)
    f = tmp_path / "sw.toml"
    f.write_text(
        f'name = "s"\nbase = "sensorless"\n[set]\nplugins.modules = ["{mod.name}"]\n'
        "[axes]\nspeed_rpm = [800, 1200]\n"
    )
    monkeypatch.setenv(ALLOW_ENV, "1")
    capsys.readouterr()
    assert main(["sweep", str(f), "--dry-run"]) == 0
    assert str(mod) in capsys.readouterr().out
    assert not marker.exists()


def test_run_without_permission_exits_2_naming_the_module_and_writes_nothing(tmp_path, capsys):
    mod, marker = _module(tmp_path)
    f = _scenario_file(tmp_path, [mod.name])
    out = tmp_path / "o"
    for cmd in (
        ["run", str(f), "--out", str(out), "-q"],
        ["stability", str(f), "--out", str(out)],
        ["commission", str(f), "--out", str(out)],
        ["sweep", str(f), "--out", str(out), "-q"],
    ):
        capsys.readouterr()
        rc = main(cmd)
        err = _err(capsys)
        assert rc == 2, (cmd, err)
        if cmd[0] != "sweep":  # a scenario file is not a sweep file: refused before
            assert "plugins.modules[0]" in err and str(mod) in err, (cmd, err)
        assert len(err.strip().splitlines()) == 1, err
        assert not marker.exists() and not out.exists(), cmd


def test_every_command_that_runs_a_drive_has_allow_plugins():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name in ("run", "sweep", "stability", "bench-estimators", "commission"):
        opts = {o for a in sub.choices[name]._actions for o in a.option_strings}
        assert "--allow-plugins" in opts, name
    for name in ("show", "compare"):  # they only look: never import
        opts = {o for a in sub.choices[name]._actions for o in a.option_strings}
        assert "--allow-plugins" not in opts, name


def test_allow_plugins_on_the_command_line_imports_it(tmp_path, capsys):
    mod, marker = _module(tmp_path)
    f = _scenario_file(tmp_path, [mod.name])
    # allowed, the module runs when the scenario is read; the bad --format then stops the
    # command before any drive is simulated
    capsys.readouterr()
    rc = main(
        ["run", str(f), "--out", str(tmp_path / "o"), "--format", "nosuch", "--allow-plugins"]
    )
    assert rc == 2 and "nosuch" in _err(capsys)
    assert marker.exists() and not (tmp_path / "o").exists()


def test_the_summary_records_module_hashes_and_a_rerun_warns_on_change(tmp_path):
    mod, marker = _module(tmp_path)
    hashes = module_hashes([str(mod)])
    assert len(hashes[str(mod)]) == 64
    data = Scenario.read("sensorless").to_dict()
    data["plugins"]["modules"] = [str(mod)]
    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps({"scenario": data, "plugins": hashes}))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # unchanged: no warning
        Scenario.read(str(summary), allow_plugins=True)
    mod.write_text(mod.read_text() + "# edited\n")
    with pytest.warns(ConfigWarning, match=r"plugins\.modules: .*evil\.py has changed"):
        Scenario.read(str(summary))  # imported above: in this process it runs nothing new


@pytest.mark.slow  # 1.5 s or more on 2 cores (3.7 s in the fast tier, 2026-11-29)
def test_compare_of_a_result_naming_a_module_imports_nothing(tmp_path, capsys, monkeypatch):
    from imdrive import simulate

    res = simulate(
        Scenario.read(
            "sensorless",
            ["simulation.t_end_s=0.02", "output.figures=false", "output.report=false"],
        )
    )
    res.save(tmp_path / "a")
    mod, marker = _module(tmp_path / "m")
    s = json.loads((tmp_path / "a" / "summary.json").read_text())
    s["scenario"]["plugins"]["modules"] = [str(mod)]
    (tmp_path / "a" / "summary.json").write_text(json.dumps(s))
    monkeypatch.setenv(ALLOW_ENV, "1")
    capsys.readouterr()
    rc = main(["compare", str(tmp_path / "a"), str(tmp_path / "a"), "--out", str(tmp_path / "c")])
    err = _err(capsys)
    assert rc == 0, err
    assert "not imported" in err and str(mod) in err  # named, not run
    assert not marker.exists()
