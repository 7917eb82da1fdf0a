"""Stability maps: steady state, linearisation, maps, their check by simulation.

Each test can fail: the steady state is compared with a long simulation of the engine, the
linear model with the nonlinear loop's own response, the map's verdicts with simulations from
each fixed point, and the two known instabilities of the MRAS drive must appear where they are.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from data.inprocess import imdrive_here

from imdrive.analysis.foc import foc_operating_point
from imdrive.cli import main
from imdrive.config.scenario import Scenario
from imdrive.kernels import linearise as kl
from imdrive.kernels.engine import LOG, S_OK, run_drive
from imdrive.kernels.recording import RECORDING
from imdrive.run.build import build_arrays, copy_state
from imdrive.stability.linear import (
    INPUT_NAMES,
    OUTPUT_NAMES,
    RPM,
    STATE_NAMES,
    map_scenario,
    operating_point,
)
from imdrive.stability.maps import MAP_COLUMNS, stability_map, validate_map

#: simulate()'s "no recording" (a zero-length array: the engine run shares its type)
NO_REC = np.zeros(0, dtype=RECORDING)


@pytest.fixture(scope="module")
def sensorless():
    """The sensorless preset with the paper tuning of the MRAS (wc = 5 rad/s, 40 Hz), the drive
    the measurements of docs/stability.md were made on (the defaults are tuned otherwise)."""
    return Scenario.read("sensorless", ["mras.wc_rad_s=5", "mras.bandwidth_Hz=40"])


def _long_run(preset, speed, torque, t_end=6.0, extra=()):
    """Final reduced state of the engine after a start-up to (speed, torque) and a long hold."""
    ov = [
        f"control.speed_ref_rpm={{initial=0, changes=[{{at=0.5, to={speed}, over=1.0}}]}}",
        f"load.torque_Nm={{initial=0, changes=[{{at=2.0, to={torque}, over=0.5}}]}}",
        f"simulation.t_end_s={t_end}",
        *extra,
    ]
    sc = Scenario.read(preset, ov)
    a = build_arrays(sc)
    S = copy_state(a.state0)
    st, _ = run_drive(a.params, S, 0, a.n_steps, np.empty(0, dtype=LOG), 0, 0, False, NO_REC)
    assert st == S_OK
    z = np.empty(kl.N_Z)
    kl.pack_state(a.params, S, 0, z)
    return sc, z


@pytest.mark.parametrize(
    "preset, speed, torque",
    [("sensorless", 1000, 12), ("sensorless-detuned", 1000, 12), ("sensorless", -400, -6)],
)
def test_operating_point_matches_long_simulation(preset, speed, torque):
    sc, z_sim = _long_run(preset, speed, torque)
    op = operating_point(sc, speed, torque)
    assert op.status == "ok" and op.stable
    rel = np.abs(z_sim - op.z) / (np.abs(op.z) + kl.Z_SCALE)
    assert rel.max() < 1e-5, dict(zip(STATE_NAMES, rel, strict=True))


def test_operating_point_with_the_cut_off_following_the_stator_frequency():
    # 60 rpm, 6 N m: 21 rad/s of stator frequency, the MRAS filter's cut-off at 10.4 rad/s on
    # its slope; the map holds the low-passed flux frequency at the operating point's (without
    # the hold it drifted between the map's evaluations and Newton found no fixed point)
    extra = ("mras.wc_per_stator_frequency=0.5", "mras.wc_min_rad_s=5")
    sc, z_sim = _long_run("sensorless", 60, 6, t_end=10.0, extra=extra)  # 16 time constants
    op = operating_point(sc, 60, 6)
    assert op.status == "ok" and op.stable
    rel = np.abs(z_sim - op.z) / (np.abs(op.z) + kl.Z_SCALE)
    assert rel.max() < 1e-5, dict(zip(STATE_NAMES, rel, strict=True))


def test_steady_state_generalises_the_analytic_foc_point(sensorless):
    """With only an R2_hat error the fixed point is foc_operating_point's (to sampling effects)."""
    sc = Scenario.read("sensorless-detuned")
    op = operating_point(sc, 800, 10)
    ref = foc_operating_point(sc.machine, 800, 10, R2_ratio=0.9792 / 0.816, sensorless=True)
    assert op.speed_est_rpm == pytest.approx(800, abs=1e-9)
    assert op.speed_rpm == pytest.approx(ref.speed_rpm, abs=0.05)
    assert op.current_dq_A.imag == pytest.approx(ref.iq_A, rel=5e-3)


@pytest.mark.slow
@pytest.mark.parametrize(
    "speed, torque, r1",
    [(1000, 12, 1.0), (30, -12, 1.0), (1000, 12, 1.1), (200, -6, 1.0), (-600, 8, 0.95)],
)
def test_linearisation_matches_nonlinear_responses(sensorless, speed, torque, r1):
    """A^n dz and the input response match the engine's own run to 1e-3 relative."""
    op = operating_point(map_scenario(sensorless, R1_ratio=r1), speed, torque)
    assert op.status == "ok"
    scale = np.abs(op.z) + kl.Z_SCALE
    rng = np.random.default_rng(11)
    worst = 0.0
    for n in (1, 10, 100, 400):
        dz = 1e-6 * rng.standard_normal(kl.N_Z) * scale
        nl = op.propagate(dz, n)
        lin = np.linalg.matrix_power(op.A, n) @ dz
        worst = max(worst, np.linalg.norm((nl - lin) / scale) / np.linalg.norm(lin / scale))
        for k, du in enumerate(((0.01, 0.0), (0.0, 0.001))):
            nl = op.propagate(np.zeros(kl.N_Z), n, du=du)
            x = np.zeros(kl.N_Z)
            for _ in range(n):
                x = op.A @ x + op.B[:, k] * du[k]
            worst = max(worst, np.linalg.norm((nl - x) / scale) / np.linalg.norm(x / scale))
    assert worst < 1e-3


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_statespace_names_and_response(sensorless):
    op = operating_point(sensorless, 1000, 12)
    sys_ = op.to_statespace()
    names = getattr(sys_, "input_labels", None) or sys_.input_names
    assert list(names) == list(INPUT_NAMES)
    out = getattr(sys_, "output_labels", None) or sys_.output_names
    assert list(out) == list(OUTPUT_NAMES)
    assert sys_.dt == pytest.approx(op.Ts)
    # DC gain speed_ref -> speed estimate is 1 (integral action on the estimate)
    G = op.C @ np.linalg.solve(np.eye(kl.N_Z) - op.A, op.B)
    assert G[1, 0] == pytest.approx(1.0, rel=1e-6)
    # load torque -> current i_q: the torque constant (positive, A per N m)
    k_t = 1.5 * 2 * 0.0693 / 0.0713 * op.z[12]
    assert G[3, 1] == pytest.approx(1.0 / k_t, rel=2e-2)
    modes = op.modes()
    assert modes[0].s.real < 0 and 0 <= modes[0].damping <= 1


def test_known_instabilities(sensorless):
    """Low-speed regeneration and the ~30 Hz limit cycle of an overestimated R1_hat."""
    # R1_hat/R1 at 1000 rpm, rated load: stable up to ~1.06, a 30-40 Hz mode beyond
    res = {r: operating_point(map_scenario(sensorless, R1_ratio=r), 1000, 12) for r in (1, 1.08)}
    assert res[1].stable
    assert not res[1.08].stable
    m = res[1.08].modes()[0]
    assert m.s.real > 0 and 25 < m.frequency_Hz < 40
    # with Schauder's adaptation error regenerating rated load at low speed is unstable,
    # motoring is not; the rotated error (mras.regeneration_angle_deg, the default) holds both
    schauder = sensorless.with_overrides(["mras.regeneration_angle_deg=0"])
    df = stability_map(schauder, [30, 50, 300], [-12, 12])
    v = {(r.speed_rpm, r.torque_Nm): r.stable for r in df.itertuples()}
    assert not v[(30, -12)] and not v[(50, -12)]
    assert v[(30, 12)] and v[(50, 12)] and v[(300, -12)] and v[(300, 12)]
    df = stability_map(sensorless, [30, 50], [-12])
    assert df["stable"].all()


def test_map_table_and_bad_points(sensorless):
    df = stability_map(sensorless, [500, 1000, 4000], [-60, 0, 12, 60])
    assert tuple(df.columns) == MAP_COLUMNS
    st = {(r.speed_rpm, r.torque_Nm): r.status for r in df.itertuples()}
    assert st[(4000, 0)] == "voltage_limit"
    assert st[(500, 60)] == "current_limit" and st[(500, -60)] == "current_limit"
    assert st[(1000, 12)] == "ok"
    assert not df.loc[df.status != "ok", "stable"].any()
    assert df.loc[df.status != "ok", "max_real_1_per_s"].isna().all()


def test_no_steady_state_at_zero_stator_frequency_with_R1_error(sensorless):
    """With R1_hat != R1 the unfiltered reference model has no equilibrium at w_e = 0 (Ohtani
    1992). The drive's filtered one does settle there, far off: run from the continuous guess
    it comes to rest with the estimate on the reference (72.7 rpm) and the rotor at 22.0 rpm,
    a stable fixed point the map finds by Newton's restart from the settled drive (until
    2026-11-30 it said "no steady state"); its ``speed_actual_rpm`` says how far off."""
    sc = map_scenario(sensorless, R1_ratio=1.1)
    # speed reference at which the commanded synchronous speed vanishes: n_p w + w_sl* = 0
    m = sc.machine
    i_d = m.rated_flux_Wb / m.M_H
    k_t = 1.5 * m.pole_pairs * m.M_H / m.L2_H * m.rated_flux_Wb
    w_sl = m.R2_ohm / m.L2_H * (-12 / k_t) / i_d
    speed = -w_sl / m.pole_pairs / RPM
    df = stability_map(sc, [speed], [-12])
    row = df.iloc[0]
    assert row.status == "ok" and row.stable
    assert row.speed_est_rpm == pytest.approx(speed, abs=1e-6)
    assert row.speed_est_rpm - row.speed_actual_rpm > 40.0  # measured 50.6 rpm


@pytest.mark.slow
def test_map_agrees_with_simulation(sensorless):
    """>= 200 points (speed x torque x R1_hat/R1): >= 97 % agreement, misses on the boundary."""
    speeds = [10, 20, 40, 60, 100, 200, 500, 1000, 1400]
    torques = [-18, -13.5, -9, -4.5, 0, 4.5, 9, 13.5, 18]
    table, confusion = validate_map(sensorless, speeds, torques, R1_ratios=(1.0, 1.06, 1.1))
    have = table[table.status == "ok"]
    print("\n" + confusion.to_string())
    assert len(have) >= 200
    agree = (have.stable == have.sim_stable).mean()
    miss = have[have.stable != have.sim_stable]
    print(f"agreement {agree:.4f} over {len(have)} points; misses:\n{miss.to_string()}")
    assert agree >= 0.97
    assert miss.near_boundary.all()
    # both verdicts occur (the test would pass trivially on an all-stable grid otherwise)
    assert have.stable.sum() > 20 and (~have.stable).sum() > 20


# -- command line ---------------------------------------------------------------------------


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_cli_writes_table_and_figures(tmp_path, capsys):
    out = tmp_path / "st"
    code = main(
        [
            "stability", "sensorless", "--speeds", "0:1500:6", "--torques=-20:20:5",
            "--r1-ratios", "1.1", "--out", str(out), "-q",
        ]
    )  # fmt: skip
    assert code == 0
    for f in ("stability.csv", "stability.png", "stability_R1.png"):
        assert (out / f).stat().st_size > 0
    import pandas as pd

    df = pd.read_csv(out / "stability.csv")
    assert len(df) == 60
    assert {"speed_rpm", "torque_Nm", "max_real_1_per_s", "stable", "map"} <= set(df.columns)


CLI_BAD = [
    (["--speeds", "1500:0:10"], "--speeds"),
    (["--speeds", "0:1500"], "--speeds"),
    (["--torques", "a:b:3"], "--torques"),
    (["--torques=-5:5:1"], "--torques"),
    (["--r1-ratios", "1,-1"], "--r1-ratios"),
    (["--set", "mras.wc_rad_s=-1"], "mras.wc_rad_s"),
]


@pytest.mark.parametrize("args, field", CLI_BAD)
def test_cli_bad_input(tmp_path, args, field):
    """Through ``main`` in this process (``data.inprocess``: a traceback is an exception, a
    warning a line of stderr); the next test runs one case through the real command."""
    out = tmp_path / "x"
    p = imdrive_here("stability", "sensorless", *args, "--out", out, cwd=tmp_path)
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0], p.stderr
    assert not out.exists()


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_cli_bad_input_from_the_real_command(tmp_path):
    args, field = CLI_BAD[0]
    out = tmp_path / "x"
    p = subprocess.run(
        [sys.executable, "-m", "imdrive", "stability", "sensorless", *args, "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0], p.stderr
    assert not out.exists()


def test_rpm_constant():
    assert RPM == pytest.approx(math.pi / 30)


@pytest.mark.parametrize(
    "override, field",
    [
        ("inverter.model=switching", "inverter.model"),
        ("inverter.dead_time_s=2e-6", "inverter.dead_time_s"),
        ("sensor.gain_a=1.01", "sensor"),
        ("control.delay_periods=1", "control.delay_periods"),
    ],
)
def test_settings_outside_the_linear_model_are_refused(override, field):
    from imdrive.config.scenario import Scenario
    from imdrive.errors import ConfigError
    from imdrive.stability import stability_map

    with pytest.raises(ConfigError) as exc:
        stability_map(Scenario.read("sensorless", [override]), [500.0], [6.0])
    assert exc.value.field == field


def test_the_default_drive_is_unstable_in_regeneration_only_next_to_zero_stator_frequency():
    """The default ``sensorless`` preset (rotated adaptation error in regeneration): the
    regenerating points up to rated torque that stay unstable lie within 0.05 Hz of stator
    frequency of the line of zero stator frequency, where the speed is unobservable; with Schauder's
    error the whole quadrant below that line is unstable (docs/stability.md)."""
    sc = Scenario.read("sensorless")
    m = sc.machine
    speeds = list(np.arange(6.0, 126.0, 6.0))
    torques = [-12.0, -8.0, -4.0]

    def stator_Hz(df):
        i_d = m.rated_flux_Wb / m.M_H
        k_t = 1.5 * m.pole_pairs * m.M_H / m.L2_H * m.rated_flux_Wb
        w_sl = m.R2_ohm / m.L2_H * (df["torque_Nm"] / k_t) / i_d  # slip, rad/s electrical
        return (m.pole_pairs * df["speed_rpm"] * RPM + w_sl) / (2 * math.pi)

    rot = stability_map(sc, speeds, torques)
    bad = rot[(rot.status == "ok") & ~rot.stable]
    assert len(bad) <= 4  # 2 of 60 measured, at -0.015 and -0.022 Hz
    assert (stator_Hz(bad).abs() <= 0.05).all()
    sch = stability_map(sc.with_overrides(["mras.regeneration_angle_deg=0"]), speeds, torques)
    bad = sch[(sch.status == "ok") & ~sch.stable]
    assert len(bad) >= 20 and stator_Hz(bad).min() < -1.0  # 24, down to -2.2 Hz


def test_the_map_runs_the_engine_compiled_for_run():
    """The stability kernels call the engine with ``simulate()``'s argument types: a constant
    argument reached it as a numba literal (``Literal[int](1)``), a signature of its own, and
    the first map after a warm ``imdrive run`` compiled the whole engine three more times."""
    from imdrive.run.simulate import simulate

    simulate(Scenario.read("sensorless", ["simulation.t_end_s=0.01"]))
    before = set(run_drive.signatures)
    df = stability_map(Scenario.read("sensorless"), [500.0], [6.0])
    assert list(df["status"]) == ["ok"]
    assert set(run_drive.signatures) == before  # nothing compiled (or loaded) for the map
