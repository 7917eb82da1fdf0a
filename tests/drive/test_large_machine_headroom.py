"""The estimation headroom at rated speed on the large machines of the library
(docs/machine-envelope.md).

The headroom's slow loop lowers the flux until the peak voltage use of the last whole
injection period is ``injection.headroom_voltage``; the peak is sampled once per injection
period. The injection is set in per-unit of the rotor's corner frequency, 0.15-0.22 Hz on
Krause 500 hp, 2250 hp and the 3.3 kV machine (2 Hz on Table IV), so the setting's 1 /s was a
gain of 5-14 per period: the flux cycled between rated and the field weakening's floor (no
load), and from the load step's stale peak it fell until the torque current saturated. Where
it did (rated regenerating load), the torque limit handed the flux back to the field
weakening only while the speed gate had tripped: with the gate still open the flux kept
falling and the load ran the drive away (control lost at 15-48 s).
"""

from __future__ import annotations

import warnings

import pytest

from imdrive.errors import ConfigWarning
from imdrive.run import compensator_blocks
from imdrive.run.simulate import simulate
from imdrive.studies.machines import scenarios, timeline


def _rated_speed_run(machine, load_pu, ratio, t_end_s, overrides=()):
    """The library grid's ``injection-robust`` run at rated speed, ended at ``t_end_s``.

    Returns whether control was lost and the lowest rotor flux (per-unit of the rated one)
    from 0.5 s after the load step on.
    """
    scs, _ = scenarios(
        [machine], drives=["injection-robust"], speeds=[1.0], loads=[load_pu], ratios=[ratio]
    )
    load_at = timeline(scs[0].machine)[1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        sc = scs[0].with_overrides([*overrides, f"simulation.t_end_s={t_end_s}"])
    res = simulate(sc)
    df = res.to_pandas()
    after = df["time_s"] > load_at + 0.5
    flux = float(df["flux_Wb"][after].min() / sc.machine.rated_flux_Wb)
    return bool(res.summary()["lost_control"]), flux


@pytest.mark.slow
@pytest.mark.parametrize("machine", ["krause-500hp", "geyer-3.3kv"])
def test_headroom_gain_per_injection_period_keeps_the_flux_near_rated(machine):
    # rated speed, no load, R2_hat(0) = 0.8 R2. With 1 /s (gain 7 per period) the flux fell
    # below 0.6 of rated at 17.3 s (500 hp) and 18.4 s (3.3 kV), to 0.18-0.19, and back: a
    # limit cycle of tens of seconds. At 0.6 per period (the cap of earlier releases; 0.5 per
    # period now, run/compensator_blocks.py HEADROOM_GAIN_PER_PERIOD) the lowest flux over
    # 150 s was 0.78 of rated (the headroom's few percent and the injection's 7.5 %)
    lost, flux = _rated_speed_run(machine, 0.0, 0.8, 25.0)
    assert not lost
    assert flux > 0.7, flux


@pytest.mark.slow
@pytest.mark.parametrize(("machine", "ratio"), [("krause-500hp", 0.8), ("krause-2250hp", 1.2)])
def test_headroom_yields_to_the_torque_limit_with_the_speed_gate_open(machine, ratio, monkeypatch):
    # rated speed, rated regenerating load, with the headroom's gain per period uncapped (the
    # flux driven down from the load step's peak): the torque current reaches its limit
    # before the speed gate trips. Handed back to the field weakening, the flux stops at
    # 0.63 (500 hp) and 0.65 (2250 hp) of rated and control holds; before, it fell on and
    # control was lost at 17.7 s and 24.1 s
    t_end = {"krause-500hp": 30.0, "krause-2250hp": 35.0}[machine]
    # the 1 /s of earlier releases without their cap per period
    monkeypatch.setattr(compensator_blocks, "headroom_rate_per_s", lambda f_inj_Hz: 1.0)
    lost, flux = _rated_speed_run(machine, -1.0, ratio, t_end)
    assert not lost
    assert flux > 0.5, flux
