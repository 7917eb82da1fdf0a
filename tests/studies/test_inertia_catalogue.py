"""Default rotor inertia against catalogue motors (docs/nameplate.md, "Default rotor inertia")."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from imdrive.analysis import inertia
from imdrive.studies import inertia_catalogue as ic


@pytest.fixture(scope="module")
def table():
    return ic.run()


def test_every_catalogue_row_states_its_source_and_role():
    df = ic.catalogue()
    assert len(df) >= 10
    assert df["source"].str.len().min() > 40  # document and address, not a placeholder
    assert set(df["role"]) == {"fit", "check"}
    assert (df["J_kgm2"] > 0).all() and (
        df["speed_rpm"] < 120 * df["frequency_Hz"] / df["poles"]
    ).all()
    # the fit is one manufacturer's catalogue; the check rows are other manufacturers'
    fit = df[df["role"] == "fit"]
    assert fit["manufacturer"].nunique() == 1
    assert not set(df[df["role"] == "check"]["manufacturer"]) & set(fit["manufacturer"])
    assert df["poles"].nunique() >= 2


def test_the_constants_are_the_fit_to_the_catalogue_rows():
    k, a = ic.fit_power_law()
    assert inertia.INERTIA_EXPONENT == pytest.approx(a, abs=5e-4)
    assert inertia.INERTIA_COEFFICIENT_KGM2 == pytest.approx(k, rel=5e-3)


def _fit_power_kW(table) -> float:
    return float(table[table["role"] == "fit"]["power_kW"].max())


def test_at_least_ten_catalogue_motors_within_a_factor_of_one_and_a_half(table):
    """The goal of issue 39: the default within 1.5 times the catalogue's J for at least 10
    motors; the former H = 0.5 s default meets it for none of the motors in the fit's range
    (it does for some larger ones, whose inertia constant is near 0.5 s)."""
    assert int(ic.within(table["ratio"]).sum()) >= ic.MIN_WITHIN
    in_range = table["power_kW"] <= _fit_power_kW(table)
    assert int(ic.within(table["ratio_former"][in_range]).sum()) == 0


def test_no_catalogue_motor_is_off_by_the_warning_factor(table):
    """A real rotor's J never draws the far-from-its-size warning; the fit's own motors are
    within the 1.7 that INERTIA_WARN_FACTOR's comment states."""
    assert ic.within(table["ratio"], inertia.INERTIA_WARN_FACTOR).all()
    fit = table[table["role"] == "fit"]["ratio"]
    assert fit.max() < 1.75 and fit.min() > 1 / 1.75


def test_above_the_fit_s_range_the_law_holds_on_most_large_motors(table):
    """30 kW - 1.68 MW (Motive's catalogue to 315 kW, Krause's 500 and 2250 hp), an
    extrapolation of a fit that ends at 22 kW: within 1.5 times for at least three in four
    (39 of 44 measured), no motor off by more than 2.2 times (2.10 measured, Motive 315S-8),
    and no bias either way beyond 15 % in the median (0.93 measured)."""
    big = table[table["power_kW"] > _fit_power_kW(table)]
    assert len(big) >= 40 and big["power_kW"].max() > 1000.0
    assert ic.within(big["ratio"]).sum() >= 0.75 * len(big)
    assert ic.within(big["ratio"], 2.2).all()
    assert 1 / 1.15 < np.median(big["ratio"]) < 1.15


def test_in_the_fit_s_range_the_law_runs_high_on_the_other_manufacturers_motors(table):
    """Up to 22 kW the other manufacturers' rotors (mostly Motive's) are lighter than the fit's
    SOGA rotors of the same torque: the default is above their J in the median (1.37 measured,
    1.06 on the fit) and within 1.5 times of fewer of them (39 of 66) than of the fit's (14 of
    17), though of more than half."""
    P_fit = _fit_power_kW(table)
    others = table[(table["role"] == "check") & (table["power_kW"] <= P_fit)]
    fit = table[table["role"] == "fit"]
    assert len(others) >= 60
    assert np.median(others["ratio"]) > 1.25 > np.median(fit["ratio"])
    share = ic.within(others["ratio"]).mean()
    assert 0.5 < share < ic.within(fit["ratio"]).mean()


def test_the_krause_rows_are_the_library_presets():
    """The textbook machines' rows carry the preset's own rated power, speed, poles and J."""
    from imdrive.config.machine import preset_table

    df = ic.catalogue()
    rows = df[df["manufacturer"].str.startswith("Krause")]
    assert len(rows) == 2
    for r in rows.itertuples():
        name = r.model.split("preset ")[1].rstrip(")")
        m = preset_table(name)
        assert r.power_kW * 1e3 == pytest.approx(m["rated_power_W"], rel=1e-9)
        assert r.speed_rpm == m["rated_speed_rpm"] and r.poles == 2 * m["pole_pairs"]
        assert r.frequency_Hz == m["rated_frequency_Hz"] and r.J_kgm2 == m["J_kgm2"]


def test_doc_table_is_the_rendering_of_a_fresh_run(table):
    from imdrive.studies.doctable import DOCS

    stored = pd.read_csv(DOCS / "data" / "inertia_catalogue.csv")
    assert ic.markdown(stored) == ic.markdown(table)
