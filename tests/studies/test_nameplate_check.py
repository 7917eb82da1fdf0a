"""Nameplate -> circuit on the library's published machines (docs/nameplate.md's table)."""

from __future__ import annotations

import pytest

from imdrive import machine_preset, machine_presets
from imdrive.analysis.nameplate import estimate_circuit
from imdrive.errors import ConfigError
from imdrive.studies import nameplate_check as nc

LIBRARY = list(machine_presets())


@pytest.fixture(scope="module")
def table():
    return nc.run()


@pytest.mark.parametrize("case", nc.CASES, ids=lambda c: "-".join(c))
def test_every_method_meets_the_rated_point_on_every_machine(table, case):
    rows = table[(table["method"] == case[0]) & (table["data"] == case[1])]
    assert list(rows["machine"]) == LIBRARY
    assert (rows["torque_err_pct"].abs() < 100 * nc.RATED_TOL).all()
    assert (rows["current_err_pct"].abs() < 100 * nc.RATED_TOL).all()
    assert (rows["speed_err_pu_slip"].abs() < nc.RATED_TOL).all()


@pytest.mark.parametrize("case", sorted(nc.BREAKDOWN_TOL_PCT), ids=lambda c: "-".join(c))
def test_breakdown_torque_within_the_stated_bound_on_every_machine(table, case):
    rows = table[(table["method"] == case[0]) & (table["data"] == case[1])]
    worst = rows["breakdown_err_pct"].abs().max()
    assert worst <= nc.BREAKDOWN_TOL_PCT[case], rows[["machine", "breakdown_err_pct"]]


def test_from_the_nameplate_alone_the_published_method_beats_the_assumed_breakdown(table):
    lee = table[(table["method"] == "lee") & (table["data"] == "nameplate")]
    fit = table[(table["method"] == "fit") & (table["data"] == "nameplate")]
    assert lee["breakdown_err_pct"].abs().max() < fit["breakdown_err_pct"].abs().max() / 4


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # lee, on purpose
def test_default_loss_split_leaves_a_copper_only_circuit_no_stator_copper_loss():
    """The library's efficiencies count copper losses only: the method's typical core,
    friction and stray losses do not fit in them, and it says so."""
    plate = nc.library_nameplate(machine_preset("paper-table-iv"))
    with pytest.raises(ConfigError) as err:
        estimate_circuit(plate, method="lee")
    assert err.value.field == "efficiency"


def test_doc_table_is_the_rendering_of_the_stored_measurement(table):
    import pandas as pd

    from imdrive.studies.doctable import DOCS

    stored = pd.read_csv(DOCS / "data" / "nameplate_check.csv")
    assert nc.markdown(stored) == nc.markdown(table)
