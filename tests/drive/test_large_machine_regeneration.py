"""Why the sensorless drive lost regeneration at half and rated speed on the large machines
(docs/machine-envelope.md).

Not the voltage-model MRAS's regeneration instability (docs/stability.md): that region lies
below the zero-stator-frequency line (27 rpm at rated regenerating load on Krause 500 hp),
and the linearised drive is stable at half speed. The rated regenerating load step
accelerates the machine before the speed loop answers; the type-1 estimate lags, the field
orientation runs at too large a slip, the flux falls, the torque per ampere with it, the
torque current reaches its limit and the load runs the machine away. The type-2 MRAS holds.
On the 3.3 kV machine at rated speed the loss that is left without field weakening is the
inverter's voltage: the DC link of sqrt(2) x V_rated leaves no margin for the current loops at
the step; the voltage-feedback field weakening of the envelope's sensorless drive holds it
(tests/drive/test_sensorless_voltage_limit.py).
"""

from __future__ import annotations

import warnings

import pytest

from imdrive.config.machine import rated_point
from imdrive.errors import ConfigWarning
from imdrive.run.simulate import simulate
from imdrive.studies.machines import scenarios, timeline


def _regenerating_run(machine, speed_pu, ratio, overrides=()):
    """The library grid's run (sensorless, load -1 pu), ended 1.5 s after the load step."""
    scs, _ = scenarios(
        [machine], drives=["sensorless"], speeds=[speed_pu], loads=[-1.0], ratios=[ratio]
    )
    load_at = timeline(scs[0].machine)[1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        sc = scs[0].with_overrides([*overrides, f"simulation.t_end_s={load_at + 1.5}"])
    res = simulate(sc)
    df = res.to_pandas()
    after = df["time_s"] > load_at
    flux = float(df["flux_Wb"][after].min() / sc.machine.rated_flux_Wb)
    return bool(res.summary()["lost_control"]), flux


@pytest.mark.filterwarnings("ignore::imdrive.errors.ConfigWarning")
@pytest.mark.parametrize("machine", ["krause-500hp", "krause-2250hp"])
def test_half_speed_regeneration_is_linearly_stable_with_the_type_1_mras(machine):
    from imdrive.config.scenario import Scenario
    from imdrive.stability import stability_map

    sc = Scenario.read(
        "sensorless", [f'machine.preset="{machine}"', "mras.acceleration_tracking=false"]
    )
    rp = rated_point(sc.machine)
    for ratio in (0.8, 1.2):
        df = stability_map(sc, [0.5 * rp.speed_rpm], [-rp.torque_Nm], R2_ratio=ratio)
        assert (df["status"] == "ok").all() and df["stable"].all()
        assert (df["max_real_1_per_s"] < -0.3).all()  # -0.36 to -1.1 /s


@pytest.mark.slow
@pytest.mark.parametrize("machine", ["krause-500hp", "krause-2250hp"])
def test_half_speed_regeneration_is_lost_by_the_type_1_lag_and_held_by_type_2(machine):
    lost1, flux1 = _regenerating_run(machine, 0.5, 0.8, ["mras.acceleration_tracking=false"])
    lost2, flux2 = _regenerating_run(machine, 0.5, 0.8)
    assert lost1 and flux1 < 0.7  # the flux collapses under the slip error
    assert not lost2 and flux2 > 0.9


@pytest.mark.slow
def test_rated_speed_regeneration_of_the_3_3_kv_machine_needs_voltage_margin():
    """Without field weakening: lost at the DC link of sqrt(2) x V_rated, held 10 % above it;
    with the field weakening (the envelope's sensorless drive) held at sqrt(2) x V_rated."""
    from imdrive.config.perunit import resolve
    from imdrive.config.scenario import Scenario

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        base = Scenario.read("sensorless", ['machine.preset="geyer-3.3kv"'])
    vdc = resolve(base).v_max_V * 3**0.5
    bare = "control.field_weakening=false"
    lost, _ = _regenerating_run("geyer-3.3kv", 1.0, 1.2, [bare])
    lost_margin, _ = _regenerating_run(
        "geyer-3.3kv", 1.0, 1.2, [bare, f"inverter.Vdc_V={1.1 * vdc}"]
    )
    lost_fw, _ = _regenerating_run("geyer-3.3kv", 1.0, 1.2)
    assert lost and not lost_margin and not lost_fw
