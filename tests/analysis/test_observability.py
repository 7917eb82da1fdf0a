"""R2's sensitivity to an R1_hat error (imdrive.analysis.observability), eq. (1)."""

from __future__ import annotations

import math

import pytest

import imdrive
from imdrive.analysis.observability import R1_UNCERTAINTY, r2_r1_sensitivity
from imdrive.run.status import R2_TOLERANCE, r1_note
from imdrive.studies.zero_frequency import scenarios


def test_predicted_sensitivity_is_the_voltage_models_flux_error():
    """Eq. (1) against the T-circuit: the voltage model's rotor flux from the circuit's own
    steady-state stator voltage and current, with R1_hat 1 % off, moves by ``g`` % of the
    rotor flux."""
    R1, M, L2, w_e = 0.435, 0.0693, 0.0713, 2 * math.pi * 0.5
    i_dq = complex(9.0, 6.0)  # A, rotor-flux frame
    psi = M * 9.0  # the steady rotor flux of the current model, Wb
    # (v - R1 i)/(j w_e) - sigma L1 i is the stator flux minus the leakage: (M/L2) psi
    sigma_L1 = (M + 0.002) - M * M / L2
    v = 1j * w_e * ((M / L2) * psi + sigma_L1 * i_dq) + R1 * i_dq
    lam = [(L2 / M) * ((v - r * i_dq) / (1j * w_e) - sigma_L1 * i_dq) for r in (R1, 1.01 * R1)]
    assert abs(lam[0]) == pytest.approx(psi, rel=1e-12)
    moved = abs(lam[1] - lam[0]) / psi / 0.01
    assert moved == pytest.approx(r2_r1_sensitivity(R1, M, L2, abs(i_dq), w_e, psi), rel=1e-12)
    assert r2_r1_sensitivity(R1, M, L2, abs(i_dq), 0.0, psi) == math.inf


def test_the_status_reads_no_flux_as_no_figure():
    from imdrive.run.status import run_status

    m = {k: None for k in ("speed_error_pu_slip", "speed_tolerance_rpm", "verdict", "verdict_ok")}
    m |= {"verdict_text": "", "verdict_at_s": None, "R2_held_pct": 0.0, "R2_held_since_s": None}
    m |= {"R2_held_causes": None, "R2_held_end_causes": None}
    for g, want in ((math.nan, None), (math.inf, "inf"), (3.5, 3.5)):
        v = run_status(m, {}, g)
        assert v["R2_R1_sensitivity"] == want
        assert (v["R2_R1_note"] is None) is (want is None)
    assert math.isnan(r2_r1_sensitivity(0.4, 0.07, 0.072, 10.0, 3.0, 0.0))  # no flux


def test_the_note_speaks_where_a_1_percent_R1_error_exceeds_the_tolerance():
    edge = R2_TOLERANCE / R1_UNCERTAINTY
    assert r1_note(None) is None and r1_note(0.99 * edge) is None
    assert "moves R2_hat by about 2.0 %" in r1_note(1.01 * edge)
    assert "R2 weakly observable here" in r1_note(3.5)
    assert "not observable here" in r1_note(math.inf)


@pytest.mark.slow
@pytest.mark.parametrize(
    "machine, f_s_Hz, noted",
    [("paper-table-iv", 0.5, True), ("paper-table-iv", 2.0, False), ("aalto-2.2kw", 1.0, True)],
)
def test_a_run_reports_the_sensitivity_at_its_operating_point(machine, f_s_Hz, noted):
    """The recommended drive regenerating the rated torque at a stator frequency: its status
    carries eq. (1) at the final operating point, within 5 % of the study's prediction from
    the circuit at the flux reference (3.5 and 0.87 on Table IV at 0.5 and 2 Hz, 4.1 on the
    Aalto machine at 1 Hz), and the note only where a 1 % R1 error would move R2_hat beyond
    the tolerance. (On Krause 500 hp at 2 Hz the run's own point gives 0.73 against 0.63: its
    flux settles 5 % under the reference, its current 5 % over, its frequency at 1.9 Hz.)"""
    from imdrive.studies.zero_frequency import predicted_sensitivity

    scs, _ = scenarios([machine], (f_s_Hz,), (1.0,), drives=["injection-robust"])
    v = imdrive.simulate(scs[0]).verdict
    assert v["R2_R1_sensitivity"] == pytest.approx(predicted_sensitivity(machine, f_s_Hz), rel=0.05)
    assert (v["R2_R1_note"] is not None) is noted
