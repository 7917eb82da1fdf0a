"""The per-unit rates of the R2-tracking preset on the library machines: the online R1 law's
rate per-unit of the machine's rotor corner R2/L2 (``mras.R1_rate_pu``) and the estimation
headroom's gain set per injection period (run/compensator_blocks.py HEADROOM_GAIN_PER_PERIOD),
as the drive's records receive them."""

from __future__ import annotations

import math
import warnings

import pytest

from imdrive.config.perunit import resolve
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError, ConfigWarning
from imdrive.run.blocks import headroom_rate_per_s
from imdrive.run.build import build_arrays


def _robust(machine, *overrides):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        return Scenario.read("injection-robust", [f'machine.preset="{machine}"', *overrides])


def _robust_mras(machine, *overrides):
    """The recommended drive on the MRAS, whose online R1 law these tests are about (the
    preset runs the adaptive observer since 2026-11-30)."""
    return _robust(machine, 'control.speed_feedback="mras"', *overrides)


@pytest.mark.parametrize("machine", ["paper-table-iv", "krause-500hp", "geyer-3.3kv"])
def test_r1_rate_keeps_its_ratio_to_the_injection(machine):
    sc = _robust_mras(machine)
    arrays = build_arrays(sc)
    k_R1 = float(arrays.params.est["k_R1"][0])
    assert arrays.derived["mras_R1_rate_per_s"] == pytest.approx(k_R1)
    # the injection's lowest angular frequency is 0.915 of the corner R2_hat(0)/L2_hat, here
    # 1.2 times the machine's: 42 times the rate on every machine
    w_inj = 2.0 * math.pi * resolve(sc).inj_f1
    assert w_inj / k_R1 == pytest.approx(0.915 * 1.2 / 0.02621, rel=2e-3)
    if machine == "paper-table-iv":
        assert k_R1 == pytest.approx(0.3, rel=3e-4)  # the value the envelope was measured with


def test_r1_rate_in_the_old_key_replaces_the_presets_per_unit_rate():
    # the key of the last release on the preset that states its per-unit twin (config/pairs.py)
    sc = _robust_mras("paper-table-iv", "mras.R1_rate_per_s=0.5")
    assert sc.mras.R1_rate_pu is None
    assert float(build_arrays(sc).params.est["k_R1"][0]) == 0.5
    with pytest.raises(ConfigError, match="mras.R1_rate_pu"):  # both in one layer: refused
        _robust_mras("paper-table-iv", "mras.R1_rate_per_s=0.3", "mras.R1_rate_pu=0.02")


@pytest.mark.parametrize(
    "machine, f_max",
    [("paper-table-iv", 30.0), ("krause-50hp", 30.0), ("aalto-2.2kw", 25.0), ("geyer-3.3kv", 25.0)],
)
def test_r1_law_bound_is_half_the_rated_frequency(machine, f_max):
    sc = _robust_mras(machine)
    assert sc.machine.rated_frequency_Hz == 2.0 * f_max
    # exactly the 30 Hz the law was measured with on Table IV (the preset baseline)
    assert float(build_arrays(sc).params.est["R1_fmax"][0]) == f_max
    # the absolute twin of the last release still sets it
    sc = _robust_mras(machine, "mras.R1_max_freq_Hz=20")
    assert float(build_arrays(sc).params.est["R1_fmax"][0]) == 20.0


def test_headroom_gain_is_set_per_injection_period():
    assert headroom_rate_per_s(2.0) == 1.0  # Table IV's preset: its 1 /s
    assert headroom_rate_per_s(0.15) == pytest.approx(0.075)
    for machine in ("paper-table-iv", "krause-500hp", "krause-2250hp"):
        sc = _robust(machine)
        rate = float(build_arrays(sc).params.comp["inj_fw_rate"][0])
        assert rate / resolve(sc).inj_f1 == pytest.approx(0.5)
