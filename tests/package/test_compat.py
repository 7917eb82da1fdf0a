"""The 0.1 import paths keep working for one release, each with a DeprecationWarning."""

import importlib
import sys

import pytest

# old module -> names users' scripts of 0.1 imported from it
OLD_PATHS = {
    "imdrive.scenario": ["Scenario", "preset_names", "preset_text", "scenario_text"],
    "imdrive.simulate": ["simulate", "build_arrays", "logged_rows"],
    "imdrive.batch": ["simulate_batch", "BatchResult", "COLUMNS", "METRICS"],
    "imdrive.result": ["SimulationResult", "columns_from_log"],
    "imdrive.machine": ["MachineParams", "machine_preset", "machine_presets"],
    "imdrive.inverter": ["InverterParams", "limit_magnitude"],
    "imdrive.profiles": ["Profile", "parse_profile", "pwl_eval", "profiles_to_arrays"],
    "imdrive.control": ["default_current_gains", "default_speed_gains", "foc_step"],
    "imdrive.mras": ["default_mras_gains", "mras_step"],
    "imdrive.compensator": ["compensator_step", "compensator_update"],
    "imdrive.engine": ["run_drive", "DRIVE_FOC"],
    "imdrive.layout": ["S_OK", "S_NAN", "S_CURRENT", "S_SPEED", "PR_SPEED_REF"],
    "imdrive.paper": ["run_all", "COMPENSATION_PRESETS"],
    "imdrive.plots": ["save_figures", "compensation_figure"],
}


@pytest.mark.parametrize("old", sorted(OLD_PATHS))
def test_old_import_path_works_and_warns(old):
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=old.replace(".", r"\.") + " is deprecated"):
        mod = importlib.import_module(old)
    for name in OLD_PATHS[old]:
        assert hasattr(mod, name), f"{old}.{name}"


def test_old_and_new_paths_give_the_same_objects():
    with pytest.warns(DeprecationWarning):
        sys.modules.pop("imdrive.scenario", None)
        from imdrive.scenario import Scenario as Old
    from imdrive.config.scenario import Scenario

    assert Old is Scenario


def test_packages_keep_their_0_1_names_without_warning():
    # fuzzy, analysis and sweep became packages: their names are re-exported, not deprecated
    import imdrive.analysis as an
    import imdrive.fuzzy as fz
    import imdrive.sweep as sw

    assert callable(fz.fuzzy_table) and callable(an.equivalent_circuit)
    assert callable(sw.run_sweep) and callable(sw.load_sweep)


def test_readme_example_of_0_1_still_runs():
    with pytest.warns(DeprecationWarning):
        sys.modules.pop("imdrive.scenario", None)
        sys.modules.pop("imdrive.simulate", None)
        from imdrive.scenario import Scenario
        from imdrive.simulate import simulate
    res = simulate(Scenario.read("sensorless-detuned", ["simulation.t_end_s=0.2"]))
    df = res.to_pandas()
    assert list(df.columns[:3]) == ["time_s", "speed_rpm", "w_m_rad_s"]
    assert {"speed_est_rpm", "R2_hat_ohm", "e_d0_Wb"} <= set(df.columns)
    with pytest.warns(DeprecationWarning, match="R2_hat_ohm"):
        assert res["R2_est_ohm"] is res["R2_hat_ohm"]  # the 0.1 README's column name


def test_top_level_simulate_stays_callable_after_the_old_module_is_imported():
    import imdrive as im

    with pytest.warns(DeprecationWarning):
        sys.modules.pop("imdrive.simulate", None)
        importlib.import_module("imdrive.simulate")
    sc = im.Scenario.read("sensorless", ["simulation.t_end_s=0.01"])
    assert im.simulate(sc).time_s[-1] == pytest.approx(0.01)
