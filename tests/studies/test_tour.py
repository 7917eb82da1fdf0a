"""The library tour (docs/machines.md): every library machine with three presets and only the
machine changed."""

from __future__ import annotations

import pandas as pd
import pytest

from imdrive.config.machine import machine_presets
from imdrive.studies import tour
from imdrive.studies.doctable import DOCS


def _stored() -> pd.DataFrame:
    return pd.read_csv(DOCS / "data" / "library_tour.csv", keep_default_na=False)


def test_every_machine_runs_every_preset_with_no_warning_and_ends_ok():
    t = _stored()
    assert set(t["machine"]) == set(machine_presets())
    assert set(t["preset"]) == set(tour.PRESETS)
    assert (t["warnings"] == "").all(), t[t["warnings"] != ""][["machine", "preset"]]
    assert (t["verdict"] == "ok").all(), t[t["verdict"] != "ok"][["machine", "preset"]]
    tracked = t[t["preset"] == "injection-robust"]
    assert tracked["R2_error_pct"].astype(float).abs().max() < 2.0


def test_the_tracking_time_follows_the_machine():
    """20 decision windows: 14 s on Table IV, longer on the slower rotors (the injection's
    frequency and its windows follow the rotor's corner)."""
    t = _stored().set_index(["machine", "preset"])["simulated_s"].astype(float)
    assert t["paper-table-iv", "injection-robust"] == pytest.approx(14.0)
    assert t["krause-2250hp", "injection-robust"] > 10 * t["paper-table-iv", "injection-robust"]


@pytest.mark.slow
def test_reduced_run_reproduces_the_stored_tour():
    fresh = tour.run(["krause-500hp"], presets=("injection-robust", "sensorless-realistic"))
    stored = _stored()
    both = fresh.merge(stored, on=["machine", "preset"], suffixes=("", "_stored"))
    assert len(both) == 2
    for _, r in both.iterrows():
        assert r["verdict"] == r["verdict_stored"]
        for col in ("R2_error_pct", "speed_error_rpm", "simulated_s"):
            assert float(r[col]) == pytest.approx(float(r[col + "_stored"]), rel=1e-6, abs=1e-9), (
                "run 'python -m imdrive.studies.doctables --run library-tour'"
            )
