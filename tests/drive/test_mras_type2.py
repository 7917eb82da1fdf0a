"""The MRAS's type-2 adaptation (``mras.acceleration_tracking``) and its per-unit default.

The type-1 MRAS (PI adaptation, pole-zero cancelled) lags a constant acceleration by
``alpha / a``; its error signal is linear only within the rotor's corner frequency ``1/T2``,
and the indirect field orientation running on the estimate misplaces its slip by the lag.
On the large machines of the library (``1/T2`` of 2-6 rpm) the lag of a ramp to rated speed
exceeds ``1/T2``, the flux rises and control is lost; the second integral removes the lag
(docs/machine-envelope.md).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from imdrive.config.machine import machine_presets
from imdrive.config.mras_bandwidth import mras_bandwidth_Hz
from imdrive.config.perunit import MRAS_RAMP_LAG_MAX_PU, mras_ramp_lag_pu
from imdrive.config.scenario import Scenario
from imdrive.design.gains import default_mras_gains, mras_type2_gains
from imdrive.errors import ConfigWarning
from imdrive.run.simulate import simulate


def _read(preset, overrides=()):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        return Scenario.read(preset, list(overrides))


def _ramp_lag_of_linear_loop(gains, T2, a, alpha, t_end=1.0, dt=1e-4):
    """Speed minus estimate at the end of a ramp of ``alpha`` (rad/s^2), the MRAS reduced to
    its linearisation ``e = |lam|^2 T2 / (1 + s T2) (w - w_hat)`` at ``|lam| = 1``; ``gains``
    ``(K1, K2)`` or ``(K1, K2, b)`` (the second integrator after the PI)."""
    K1, K2, b = (*gains, 0.0)[:3]
    x = int_e = int_u = w_hat = 0.0  # x: the error signal's first-order state
    for k in range(int(t_end / dt)):
        w = alpha * k * dt
        x += dt * (T2 * (w - w_hat) - x) / T2
        int_e += dt * x
        u = K1 * x + K2 * int_e
        int_u += dt * u
        w_hat = u + b * int_u
    return alpha * t_end - w_hat


def test_the_second_integral_removes_the_lag_of_the_linearised_loop():
    T2, a, alpha = 1.6, 2 * math.pi * 20.0, 300.0
    lag1 = _ramp_lag_of_linear_loop(default_mras_gains(1.0, T2, a), T2, a, alpha)
    lag2 = _ramp_lag_of_linear_loop(mras_type2_gains(1.0, T2, a), T2, a, alpha)
    assert lag1 == pytest.approx(alpha / a, rel=0.01)  # type 1: alpha / a
    assert abs(lag2) < 1e-3 * alpha / a  # type 2: none
    # and the peak of the transient is 2 alpha / (e a) (docstring of mras_type2_gains)
    peak = max(
        _ramp_lag_of_linear_loop(mras_type2_gains(1.0, T2, a), T2, a, alpha, t_end=t)
        for t in np.linspace(0.005, 0.05, 46)
    )
    assert peak == pytest.approx(2 * alpha / (math.e * a), rel=0.02)


def test_the_default_follows_the_per_unit_lag_and_keeps_table_iv_type_1():
    on = {}
    for name in machine_presets():
        sc = _read("sensorless", [f'machine.preset="{name}"', "simulation.t_end_s=0.001"])
        m = sc.machine
        T2 = (m.Ll2_H + m.M_H) / m.R2_ohm
        d = simulate(sc).derived
        on[name] = "mras_b2" in d
        assert on[name] == (mras_ramp_lag_pu(sc, mras_bandwidth_Hz(sc), T2) > MRAS_RAMP_LAG_MAX_PU)
        # the PI's gains are the type-1 loop's, with or without the second integrator
        assert d["mras_K2"] == d["mras_K1"] / T2
    assert on == {
        "paper-table-iv": False,
        "krause-3hp": False,
        "krause-50hp": False,
        "krause-500hp": True,
        "krause-2250hp": True,
        "aalto-2.2kw": True,
        "geyer-3.3kv": True,
    }
    # stated explicitly, it wins over the rule
    sc = _read(
        "sensorless",
        ['machine.preset="paper-table-iv"', "mras.acceleration_tracking=true"],
    )
    assert "mras_b2" in simulate(sc.with_overrides(["simulation.t_end_s=0.001"])).derived


@pytest.mark.filterwarnings("ignore::imdrive.errors.ConfigWarning")
def test_stability_maps_linearise_the_type_2_mras():
    """Refused until round 4; its second integrator is in the reduced state now (the
    linearisation and the map against the time domain: tests/stability/test_type2_map.py)."""
    from imdrive.stability import stability_map

    sc = _read("sensorless", ['machine.preset="krause-500hp"'])
    m = stability_map(sc, [900.0], [0.0])
    assert list(m["status"]) == ["ok"] and bool(m["stable"].iloc[0])


def _ramp(machine, tracking):
    """Rated-speed ramp of the library study (no load, R2_hat = R2), up to 60 % of it. No load
    is stated: the preset's is per-unit of the machine, whose rated load at 2 s (12 N m on
    every machine when it was stated in N m) hit Krause 500 hp at standstill before its
    3.13 s start and the drive ran backwards (the estimate 409 rpm ahead)."""
    from imdrive.config.machine import rated_point
    from imdrive.studies.machines import ramp_start_s, timeline

    base = _read("sensorless", [f'machine.preset="{machine}"'])
    rp = rated_point(base.machine)
    ramp, start = timeline(base.machine)[0], ramp_start_s(base.machine)
    sc = _read(
        "sensorless",
        [
            f'machine.preset="{machine}"',
            f"mras.acceleration_tracking={str(tracking).lower()}",
            f"control.speed_ref_rpm={{initial=0, changes=[{{at={start}, to={rp.speed_rpm}, "
            f"over={ramp}}}]}}",
            "load.torque_Nm=0",
            f"simulation.t_end_s={start + 0.6 * ramp}",
        ],
    )
    df = simulate(sc).to_pandas()
    ref = df["speed_ref_rpm"] / rp.speed_rpm
    during = (ref > 0.05) & (ref < 0.5)
    lag = float((df["speed_rpm"] - df["speed_est_rpm"])[during].median())
    T2 = (base.machine.Ll2_H + base.machine.M_H) / base.machine.R2_ohm
    corner_rpm = 30.0 / (math.pi * T2 * base.machine.pole_pairs)
    flux = float(df["flux_Wb"].max() / base.machine.rated_flux_Wb)
    return lag / corner_rpm, flux


@pytest.mark.slow
@pytest.mark.parametrize("machine", ["krause-500hp", "krause-2250hp"])
def test_on_a_large_machine_the_type_1_lag_overfluxes_and_type_2_does_not(machine):
    lag1, flux1 = _ramp(machine, False)
    lag2, flux2 = _ramp(machine, True)
    # type 1: the lag exceeds the rotor's corner frequency and the flux rises by half
    assert lag1 > 1.0 and flux1 > 1.4
    # type 2: a tenth of it at most, the flux within 15 % of rated (1.10-1.11 measured: it
    # rises while the second integrator is held, below 5 % of the rated frequency)
    assert abs(lag2) < 0.1 and flux2 < 1.15


@pytest.mark.slow
def test_the_second_integrator_is_held_at_low_stator_frequency():
    """Krause 2250 hp starting to 10 % of rated speed, R2_hat = 1.2 R2: run through the start,
    where the voltage model has little signal, the type-2 loop turns the start-up ringing into
    an excursion of hundreds of rpm and control is lost; held below 5 % of the rated
    frequency (the default), the estimate stays within 60 rpm and control holds."""
    from imdrive.studies.machines import scenarios

    scs, _ = scenarios(["krause-2250hp"], drives=["sensorless"], speeds=[0.1], loads=[0.0])
    sc = scs[1]  # R2_hat(0) = 1.2 R2
    figures = {}
    for from_pu in (0.0, 0.05):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConfigWarning)
            # Schauder's error: through the start the speed estimate and the stator frequency
            # pass zero with opposite signs, where the rotated error (the default) also
            # catches the excursion, so the first case would not lose control
            run = sc.with_overrides(
                [
                    f"mras.acceleration_tracking_from_pu={from_pu}",
                    "simulation.t_end_s=9.5",
                    "mras.regeneration_angle_deg=0",
                ]
            )
        res = simulate(run)
        df = res.to_pandas()
        err = float((df["speed_rpm"] - df["speed_est_rpm"]).abs().max())
        figures[from_pu] = (err, bool(res.summary()["lost_control"]))
    assert figures[0.0][0] > 300.0 and figures[0.0][1]
    assert figures[0.05][0] < 60.0 and not figures[0.05][1]
