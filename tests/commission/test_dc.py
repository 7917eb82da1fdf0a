"""The standstill DC test's reading of the current sensors' relative gain (commission/dc.py):
the beta voltage's slope over the plateau levels, per alpha slope, is
``(1 - g_a/g_b)/sqrt 3`` while the controller holds its measured current on the alpha axis.

Measured 2026-11-30 on ``sensorless-realistic`` (12-bit ADC, 20 mA noise and offsets, dead
time and device drop): within 2.1e-4 of the plant's ratio on Table IV, the Aalto 2.2 kW and
Krause 50 hp machines, for a 0.5 % mismatch of either sign, 2 % and none; 1.6e-3 on Krause
2250 hp, where the ADC's quantum (0.7 A) is larger than the noise that would dither it.
"""

from __future__ import annotations

import warnings

import pytest

from imdrive.commission.base import guess_model, nameplate
from imdrive.commission.dc import dc_test
from imdrive.commission.rotor_time import rotor_time_test
from imdrive.config.scenario import Scenario


def _ratio(machine: str, gain_a: float, gain_b: float) -> float:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sc = Scenario.read(
            "sensorless-realistic",
            [f'machine.preset="{machine}"', f"sensor.gain_a={gain_a}", f"sensor.gain_b={gain_b}"],
        )
    npl = nameplate(sc)
    model = guess_model(npl)
    T2 = rotor_time_test(sc, npl, model).T2_s
    return dc_test(sc, npl, model, T2).gain_b_per_a


@pytest.mark.parametrize(
    ("machine", "gain_a", "gain_b"),
    [
        ("paper-table-iv", 1.0025, 0.9975),
        ("paper-table-iv", 0.99, 1.01),
        ("aalto-2.2kw", 0.9975, 1.0025),
        ("krause-50hp", 1.0025, 0.9975),
        ("krause-50hp", 1.004, 1.004),  # a common error: no relative gain
    ],
)
def test_the_dc_test_finds_the_current_sensors_relative_gain(machine, gain_a, gain_b):
    assert _ratio(machine, gain_a, gain_b) == pytest.approx(gain_b / gain_a, rel=5e-4)
