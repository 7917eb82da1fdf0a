"""The library envelope (imdrive.studies.machines): its docs table is the rendering of the
stored runs, and the grid's pipeline works on a reduced grid of two machines."""

from __future__ import annotations

import pandas as pd
import pytest

from imdrive.studies import machines as study


def test_docs_table_is_the_rendering_of_the_stored_runs():
    table = study.markdown(pd.read_csv(study.CSV))
    text = study.PAGE.read_text()
    assert study.page_with_table(text, table) == text, (
        "docs/machine-envelope.md is stale: run "
        "'python -m imdrive.studies.machines docs/data/machine_envelope.csv'"
    )


def test_the_stored_runs_cover_the_whole_library_and_grid():
    from imdrive.config.machine import machine_presets

    t = pd.read_csv(study.CSV)
    per = len(study.SPEEDS_PU) * len(study.LOADS_PU) * len(study.R2_RATIOS)
    assert set(t["machine"]) == set(machine_presets())
    assert (t.groupby(["machine", "drive"]).size() == per).all()
    assert set(t["verdict"]) <= {"converged", "not converged", "lost"}


@pytest.mark.slow
def test_reduced_grid_on_two_machines():
    t = study.run(
        ["paper-table-iv", "aalto-2.2kw"],
        drives=("sensorless",),
        speeds=(0.5,),
        loads=(1.0,),
        ratios=(1.2,),
    )
    assert len(t) == 2
    # half speed, rated load, R2_hat = 1.2 R2: both hold the speed the detuning law predicts
    assert (t["verdict"] == "converged").all(), t[
        ["machine", "speed_error_rpm", "detuning_law_rpm"]
    ]
    # the law's error is +20 % of each machine's own rated slip (Table IV 79 rpm, Aalto 61 rpm)
    assert t["detuning_law_rpm"].between(8.0, 20.0).all()


def test_a_sweep_axis_over_machines_keeps_the_settings_per_unit():
    """``"machine.preset"`` as an axis: each run gets its machine, the DC link of its rated
    voltage and the starting R2 error as a ratio of its own R2."""
    import warnings

    from imdrive.errors import ConfigWarning
    from imdrive.sweep import parse_sweep

    sweep = parse_sweep(
        """
        name = "library"
        base = "injection-robust"
        [axes]
        "machine.preset" = { values = ["paper-table-iv", "krause-50hp", "aalto-2.2kw"] }
        R2_ratio = [0.8, 1.2]
        """
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConfigWarning)  # nothing tuned for another machine
        runs = [sweep.scenario(i) for i in range(6)]
    from imdrive.config.perunit import resolve

    for sc, (machine, ratio) in zip(
        runs,
        [(m, r) for m in ("paper-table-iv", "krause-50hp", "aalto-2.2kw") for r in (0.8, 1.2)],
        strict=True,
    ):
        assert sc.machine_preset == machine
        assert sc.inverter.Vdc_V == pytest.approx(sc.machine.rated_voltage_V * 2**0.5)
        assert resolve(sc).R2_hat == pytest.approx(ratio * sc.machine.R2_ohm)


@pytest.mark.slow
def test_large_machine_is_lost_by_the_estimate_lag_not_by_the_machine():
    """krause-500hp at rated speed, no load, R2_hat = R2: with the MRAS the speed estimate lags
    the ramp by a good part of the rated slip, the plant over-fluxes and control is lost; with
    the measured speed the flux stays at rated and control holds (docs/machine-envelope.md)."""
    d = study.ramp_diagnosis(
        [("krause-500hp", "mras", 1.0, 0.5), ("krause-500hp", "measured", 1.0, 0.5)]
    )
    mras, measured = d.iloc[0], d.iloc[1]
    assert mras["lost"] and mras["lag_pu_slip"] > 0.3 and mras["max_flux_pu"] > 1.5
    assert mras["voltage_limit_at_pu"] < 0.7  # the inverter's limit at about half speed
    assert not measured["lost"] and measured["max_flux_pu"] < 1.05
