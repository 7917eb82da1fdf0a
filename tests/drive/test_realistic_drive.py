"""The realistic drive: switching bridge, dead time, delay, sensors, saturation.

Each test compares imdrive with something computed independently of its kernels: an SVPWM
bridge and machine written here and integrated by scipy's solve_ivp with the switching instants
as breakpoints, the analytical ripple of SVPWM, the dead-time volt-second law, the saturated
T-circuit solved by brentq, the sensor-gain theory.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.kernels.engine import MAX_EVENTS, switching_period
from imdrive.kernels.recording import RECORDING
from imdrive.run.build import build_arrays, copy_state
from imdrive.run.simulate import simulate

SQ3 = math.sqrt(3.0)
OPEN_LOOP = ["output.figures=false", "simulation.log_every=1"]


def _sc(preset, *overrides):
    return Scenario.read(preset, [*OPEN_LOOP, *overrides])


# --------------------------------------------------------------------------------------------
# an independent SVPWM bridge and machine


def _svpwm_segments(v_a, v_b, Vdc, Ts):
    """(start, stop, v_alpha, v_beta) of one period: min-max injection, symmetric carrier."""
    ph = np.array([v_a, -0.5 * v_a + SQ3 / 2 * v_b, -0.5 * v_a - SQ3 / 2 * v_b])
    v0 = -0.5 * (ph.max() + ph.min())
    d = np.clip(0.5 + (ph + v0) / Vdc, 0.0, 1.0)
    on, off = (1 - d) * Ts / 2, (1 + d) * Ts / 2
    cuts = np.unique(np.concatenate([[0.0, Ts], on, off]))
    segs = []
    for t0, t1 in zip(cuts[:-1], cuts[1:], strict=True):
        if t1 - t0 <= 0:
            continue
        tm = 0.5 * (t0 + t1)
        pole = np.where((tm >= on) & (tm < off), 0.5, -0.5) * Vdc
        va = 2 / 3 * (pole[0] - 0.5 * (pole[1] + pole[2]))
        vb = (pole[1] - pole[2]) / SQ3
        segs.append((t0, t1, va, vb))
    return segs


def _machine_rhs(m):
    L1, L2, M = m.Ll1_H + m.M_H, m.Ll2_H + m.M_H, m.M_H
    inv = np.linalg.inv(np.array([[L1, M], [M, L2]]))

    def rhs(t, y, va, vb):
        ps, pr = y[0:2], y[2:4]
        i_s = inv[0, 0] * ps + inv[0, 1] * pr
        i_r = inv[1, 0] * ps + inv[1, 1] * pr
        w_r = m.pole_pairs * y[4]
        dps = np.array([va, vb]) - m.R1_ohm * i_s
        dpr = -m.R2_ohm * i_r + w_r * np.array([-pr[1], pr[0]])
        Te = 1.5 * m.pole_pairs * (ps[0] * i_s[1] - ps[1] * i_s[0])
        return np.concatenate([dps, dpr, [Te / m.J_kgm2]])

    return rhs, inv


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_switching_matches_solve_ivp_with_switching_instants_as_breakpoints():
    sc = _sc("free-acceleration", "inverter.model=switching", "simulation.t_end_s=0.02")
    res = simulate(sc)
    m = sc.machine
    Ts, Vdc = sc.simulation.Ts_s, sc.inverter.Vdc_V
    rhs, inv = _machine_rhs(m)
    y = np.zeros(5)
    i_ref = [np.zeros(2)]
    for k in range(sc.simulation.n_steps):
        va, vb = res["v_ref_alpha_V"][k], res["v_ref_beta_V"][k]
        for t0, t1, sa, sb in _svpwm_segments(va, vb, Vdc, Ts):
            sol = solve_ivp(
                rhs, (t0, t1), y, method="DOP853", rtol=1e-11, atol=1e-12, args=(sa, sb)
            )
            y = sol.y[:, -1]
        i_ref.append(inv[0, 0] * y[0:2] + inv[0, 1] * y[2:4])
    i_ref = np.array(i_ref)
    got = np.column_stack([res["i_alpha_A"], res["i_beta_A"]])
    err = np.max(np.abs(got - i_ref))
    assert np.max(np.abs(i_ref)) > 50.0  # the inrush is a hard test
    assert err <= 1e-4, err


def _dead_time_reference(sc, res, rhs, stator_current, t_d, drop):
    """Stator currents at the sampling instants of the bridge with dead time ``t_d`` and device
    drops ``drop`` written here from the rule (a gate change towards the state the current's
    diode imposes is immediate, the other way it waits t_d; the drop opposes the current),
    integrated by solve_ivp event by event from ``rhs`` on ``res``'s voltage references."""
    Ts, Vdc = sc.simulation.Ts_s, sc.inverter.Vdc_V
    T = np.array([[1, 0], [-0.5, SQ3 / 2], [-0.5, -SQ3 / 2]])  # phase currents from alpha-beta

    def phase_i(y):
        return T @ stator_current(y)

    y = np.zeros(5)
    pole = np.zeros(3)
    pending: dict[int, tuple[float, float]] = {}
    i_ref = [np.zeros(2)]
    for k in range(sc.simulation.n_steps):
        va, vb = res["v_ref_alpha_V"][k], res["v_ref_beta_V"][k]
        ph = T @ np.array([va, vb])
        d = np.clip(0.5 + (ph + -0.5 * (ph.max() + ph.min())) / Vdc, 0, 1)
        events = sorted(
            [((1 - d[x]) * Ts / 2, x, 1.0) for x in range(3)]
            + [((1 + d[x]) * Ts / 2, x, 0.0) for x in range(3)]
        )
        t = 0.0
        while True:
            nxt = [(tp, x, s, "pend") for x, (tp, s) in pending.items() if tp < Ts]
            nxt += [(te, x, s, "gate") for te, x, s in events if te >= t]
            nxt.append((Ts, -1, 0.0, "end"))
            te, x, s, kind = min(nxt, key=lambda e: e[0])
            if te > t:
                i_ph = phase_i(y)
                pv = (pole - 0.5) * Vdc - np.sign(i_ph) * drop
                sa = 2 / 3 * (pv[0] - 0.5 * (pv[1] + pv[2]))
                sb = (pv[1] - pv[2]) / SQ3
                sol = solve_ivp(
                    rhs, (t, te), y, method="DOP853", rtol=1e-11, atol=1e-12, args=(sa, sb)
                )
                y, t = sol.y[:, -1], te
            if kind == "end":
                break
            if kind == "pend":
                pole[x] = pending.pop(x)[1]
                continue
            events.remove((te, x, s))
            pending.pop(x, None)
            diode = 0.0 if phase_i(y)[x] >= 0 else 1.0
            pole[x] = diode
            if diode != s:
                pending[x] = (t + t_d, s)
        # a dead time running past the period's end finishes in the next period
        pending = {x: (tp - Ts, s) for x, (tp, s) in pending.items()}
        i_ref.append(stator_current(y))
    return np.array(i_ref)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_dead_time_and_device_drops_match_solve_ivp():
    """The same bridge with a 2 us dead time and 1 V device drops, written here from the
    rule (a gate change towards the state the current's diode imposes is immediate, the other
    way it waits t_d; the drop opposes the current), integrated by solve_ivp event by event."""
    t_d, drop = 2e-6, 1.0
    sc = _sc(
        "free-acceleration",
        "inverter.model=switching",
        f"inverter.dead_time_s={t_d}",
        f"inverter.device_drop_V={drop}",
        "simulation.t_end_s=0.02",
    )
    res = simulate(sc)
    rhs, inv = _machine_rhs(sc.machine)
    i_ref = _dead_time_reference(
        sc, res, rhs, lambda y: inv[0, 0] * y[0:2] + inv[0, 1] * y[2:4], t_d, drop
    )
    got = np.column_stack([res["i_alpha_A"], res["i_beta_A"]])
    assert np.max(np.abs(got - i_ref)) <= 1e-4, np.max(np.abs(got - i_ref))


def test_switching_period_average_equals_the_reference():
    res = simulate(_sc("free-acceleration", "inverter.model=switching", "simulation.t_end_s=0.1"))
    va, vr = res["v_alpha_V"][:-1], res["v_ref_alpha_V"][:-1]
    vb, vrb = res["v_beta_V"][:-1], res["v_ref_beta_V"][:-1]
    scale = np.max(np.abs(vr))
    assert np.max(np.abs(va - vr)) <= 1e-9 * scale
    assert np.max(np.abs(vb - vrb)) <= 1e-9 * scale


def test_sampled_currents_agree_with_the_average_model_within_the_sampling_error():
    """Regular sampling at the carrier peak samples the ripple at its mean: the switching
    model's samples differ from the average model's by much less than the ripple."""
    ov = ("simulation.t_end_s=1.0",)
    sw = simulate(_sc("free-acceleration", "inverter.model=switching", *ov))
    av = simulate(_sc("free-acceleration", *ov))
    late = sw.time_s >= 0.8  # steady state
    d = np.hypot(sw["i_alpha_A"] - av["i_alpha_A"], sw["i_beta_A"] - av["i_beta_A"])[late]
    amp = np.max(np.hypot(av["i_alpha_A"], av["i_beta_A"])[late])
    # the sample at the carrier peak is the ripple's mean to first order: the error left is
    # second order in Ts (measured 0.9 mA at 6.7 A)
    assert np.max(d) < 1e-3 * amp, (np.max(d), amp)


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
def test_current_ripple_at_standstill_matches_the_svpwm_formula():
    """At standstill with a DC reference V along alpha (sector boundary: one active vector),
    the alpha current's ripple is ``V (Ts - t1) / (2 sigma L1)`` peak to peak, with
    ``t1 = 1.5 V Ts / Vdc`` the time of the active vector (volt-seconds over sigma L1)."""
    V = 5.0
    sc = _sc(
        "free-acceleration",
        "inverter.model=switching",
        "plant.speed_mode=imposed",
        "plant.imposed_speed_rpm=0",
        f"open_loop.voltage_V={V / math.sqrt(2 / 3)}",
        "open_loop.frequency_Hz=0",
        "simulation.t_end_s=2.0",
    )
    a = build_arrays(sc)
    S = copy_state(a.state0)
    from imdrive.kernels.engine import run_drive
    from imdrive.run.simulate import new_log

    # to the DC steady state, with simulate()'s argument types (no engine of this test's own)
    run_drive(a.params, S, 0, a.n_steps, new_log(0), 1, 0, True, np.zeros(0, dtype=RECORDING))
    m = sc.machine
    Ts, Vdc = sc.simulation.Ts_s, sc.inverter.Vdc_V
    sigma_L1 = m.L1_H - m.M_H**2 / m.L2_H
    trace = np.zeros((2 * MAX_EVENTS, 3))
    work = np.empty(5, dtype=S.plant.dtype)
    ev = np.empty((3, MAX_EVENTS))
    p = a.params
    switching_period(
        p.inverter[0], S.inverter[0], p.plant[0], S.plant[0], V, 0.0, Vdc,
        m.R1_ohm, m.R2_ohm, 0.0, Ts, 1, work, ev, trace,
    )  # fmt: skip
    n = int(np.count_nonzero(trace[:, 0] > 0)) + 1  # interval starts: the ripple's corners
    i_a = trace[:n, 1]
    ripple = np.ptp(i_a)
    t1 = 1.5 * V * Ts / Vdc
    expected = V * (Ts - t1) / (2 * sigma_L1)
    assert abs(i_a.mean() - V / m.R1_ohm) < 0.01 * V / m.R1_ohm  # the DC steady state
    assert ripple == pytest.approx(expected, rel=0.10), (ripple, expected)


def _fundamental(t, z, f):
    """Complex amplitude of the positive-sequence component at ``f`` of a space vector."""
    return np.mean(z * np.exp(-2j * np.pi * f * t))


def _dead_time_run(model, t_d=2e-6):
    sc = _sc(
        "free-acceleration",
        f"inverter.model={model}",
        f"inverter.dead_time_s={t_d}",
        "open_loop.frequency_Hz=50",
        f"open_loop.voltage_V={220 * 50 / 60}",
        "simulation.t_end_s=1.2",
    )
    res = simulate(sc)
    w = (res.time_s >= 1.0 - 1e-9) & (res.time_s < 1.2 - 1e-9)  # 10 whole cycles at 50 Hz
    t = res.time_s[w]
    err = res["v_alpha_V"] - res["v_ref_alpha_V"] + 1j * (res["v_beta_V"] - res["v_ref_beta_V"])
    i = res["i_alpha_A"] + 1j * res["i_beta_A"]
    return sc, _fundamental(t, err[w], 50.0), _fundamental(t, i[w], 50.0)


def test_dead_time_voltage_error_fundamental_is_the_volt_second_law():
    """Each phase loses t_d f_sw Vdc against its current (a square wave): the space vector's
    fundamental is (4/pi) t_d f_sw Vdc, opposite to the current."""
    sc, E1, I1 = _dead_time_run("switching")
    u = sc.inverter.dead_time_s * sc.inverter.switching_frequency_Hz * sc.inverter.Vdc_V
    assert abs(E1) == pytest.approx(4 / np.pi * u, rel=0.10), (abs(E1), 4 / np.pi * u)
    phase = np.angle(E1 / I1)
    assert abs(abs(phase) - np.pi) < 0.2, phase  # opposes the current


def test_averaged_dead_time_reproduces_the_switching_fundamental():
    _, E_sw, _ = _dead_time_run("switching")
    _, E_av, _ = _dead_time_run("average")
    assert abs(E_av - E_sw) <= 0.05 * abs(E_sw), (E_av, E_sw)


def test_one_period_delay_applies_the_previous_reference():
    res = simulate(_sc("vector-sensored", "control.delay_periods=1", "simulation.t_end_s=0.5"))
    v, vr = res["v_alpha_V"], res["v_ref_alpha_V"]
    assert np.allclose(v[1:-1], vr[:-2], rtol=1e-12, atol=1e-9)
    assert not np.allclose(v[1:-1], vr[1:-1], rtol=1e-6)  # it is really delayed


def test_delay_with_angle_compensation_still_holds_the_speed():
    for comp in ("true", "false"):
        res = simulate(
            _sc("vector-sensored", "control.delay_periods=1", f"control.delay_compensation={comp}")
        )
        err = np.mean(res.window(2.5)["speed_rpm"] - 1000.0)
        assert abs(err) < 1.0, (comp, err)


@pytest.mark.parametrize("V_ll", [120.0, 220.0, 270.0])
def test_saturated_no_load_steady_state_follows_the_magnetising_curve(V_ll):
    """At synchronous speed the rotor carries no current: the stator current is the
    magnetising current, and the T-circuit with the saturated Lm(psi_m) (solved here by
    brentq) gives its magnitude. A 400 V DC link keeps 270 V (23 % over rated flux, deep in
    saturation) inside the linear modulation range."""
    sc = _sc(
        "free-acceleration",
        "inverter.Vdc_V=400",
        "plant.saturation.enabled=true",
        "plant.speed_mode=imposed",
        "plant.imposed_speed_rpm=1800",
        f"open_loop.voltage_V={V_ll}",
        "open_loop.frequency_Hz=60",
        "simulation.t_end_s=1.5",
    )
    res = simulate(sc)
    m, sat = sc.machine, sc.plant.saturation
    from imdrive.run.build import saturation_curve

    c = saturation_curve(sc)
    Lm0, psi_sat, S = c["Lm0"], c["psi_sat"], c["S"]
    w = 2 * np.pi * 60.0

    def i_m(psi):
        return psi / Lm0 * (1 + (psi / psi_sat) ** S)

    V = V_ll * math.sqrt(2 / 3)
    psi = brentq(lambda p: abs((m.R1_ohm + 1j * w * m.Ll1_H) * i_m(p) + 1j * w * p) - V, 1e-6, 2)
    i_sim = np.hypot(res["i_alpha_A"], res["i_beta_A"])[res.time_s >= 1.3].mean()
    assert sat.enabled
    assert i_sim == pytest.approx(i_m(psi), rel=0.005), (i_sim, i_m(psi))


def test_saturation_energy_balance_closes():
    res = simulate(_sc("free-acceleration", "plant.saturation.enabled=true"))
    e = res.energy_balance()
    resid = e["input_J"] - e["copper_loss_J"] - e["airgap_work_J"] - e["magnetic_energy_change_J"]
    assert abs(resid) <= 1e-3 * e["input_J"]


def test_same_seed_same_run_other_seed_other_run():
    ov = ("sensor.noise_rms_A=0.05", "sensor.adc_bits=12", "simulation.t_end_s=0.3")
    a = simulate(_sc("sensorless", *ov, "sensor.seed=3"))
    b = simulate(_sc("sensorless", *ov, "sensor.seed=3"))
    c = simulate(_sc("sensorless", *ov, "sensor.seed=4"))
    assert np.array_equal(a["i_alpha_meas_A"], b["i_alpha_meas_A"])
    assert np.array_equal(a["speed_rpm"], b["speed_rpm"])
    assert not np.array_equal(a["i_alpha_meas_A"], c["i_alpha_meas_A"])
    noise = a["i_alpha_meas_A"] - a["i_alpha_A"]
    assert np.std(noise) == pytest.approx(0.05, rel=0.1)


def test_sensor_gain_mismatch_gives_the_second_harmonic_torque_ripple():
    """Gains g_a != g_b make the measured current A i; the current loop forces A i = i*, so
    the true current holds a negative-sequence part a_- conj(i*) with a_- from A^-1, and the
    torque a ripple at twice the stator frequency of about 1.5 n_p (M/L2) |psi_r| |a_-| |i*|."""
    eps = 0.01
    ov = ("simulation.t_end_s=3.0", f"sensor.gain_a={1 + eps}", f"sensor.gain_b={1 - eps}")
    res = simulate(_sc("vector-sensored", *ov))
    ref = simulate(_sc("vector-sensored", "simulation.t_end_s=3.0"))
    m = ref.scenario.machine
    w = ref.time_s >= 2.5
    t = ref.time_s[w]
    i = (ref["i_alpha_A"] + 1j * ref["i_beta_A"])[w]
    f_s = np.mean(np.diff(np.unwrap(np.angle(i)))) / np.diff(t).mean() / (2 * np.pi)
    A = np.array([[1 + eps, 0.0], [2 * eps / SQ3, 1 - eps]])
    B = np.linalg.inv(A)
    a_minus = abs(0.5 * (B[0, 0] - B[1, 1]) + 0.5j * (B[1, 0] + B[0, 1]))
    psi_r = np.mean(res["flux_Wb"][w])
    theory = 1.5 * m.pole_pairs * m.M_H / m.L2_H * psi_r * a_minus * np.mean(np.abs(i))

    def amp2(r):
        T = r["torque_Nm"][w]
        return 2 * abs(np.mean((T - T.mean()) * np.exp(-2j * np.pi * 2 * f_s * t)))

    assert amp2(ref) < 0.05 * theory  # no mismatch, no 2f ripple
    assert theory / 2 <= amp2(res) <= 2 * theory, (amp2(res), theory)


@pytest.mark.parametrize(
    "override, field",
    [
        ("inverter.dead_time_s=5e-5", "inverter.dead_time_s"),
        ("inverter.dead_time_s=1e-4", "inverter.dead_time_s"),
        ("simulation.Ts_s=5e-5", "simulation.Ts_s"),
        ("sensor.adc_bits=1", "sensor.adc_bits"),
        ("sensor.noise_rms_A=-0.1", "sensor.noise_rms_A"),
        ("plant.saturation.exponent=-2", "plant.saturation.exponent"),
        ("plant.saturation.exponent=0", "plant.saturation.exponent"),
        ("control.delay_periods=2", "control.delay_periods"),
        ("control.delay_periods=-1", "control.delay_periods"),
    ],
)
def test_bad_realistic_settings_are_refused_naming_the_field(override, field):
    ovs = ["inverter.model=switching", override]
    with pytest.raises(ConfigError) as exc:
        Scenario.read("sensorless", ovs)
    assert exc.value.field == field, str(exc.value)


def test_bad_realistic_setting_on_the_command_line(tmp_path, capsys):
    from imdrive.cli import main

    out = tmp_path / "out"
    code = main(["run", "sensorless", "--out", str(out), "--set", "inverter.dead_time_s=1e-4"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "inverter.dead_time_s" in err[0]
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize(
    "name",
    [
        "sensorless-realistic",
        "paper-fig5-realistic",
        "paper-fig6-realistic",
        "injection-fig5-realistic",
        "injection-fig6-realistic",
    ],
)
def test_realistic_presets_load_with_every_non_ideality_on(name):
    from imdrive.analysis.commissioning import ideal_commissioning

    sc = Scenario.read(name)
    assert sc.inverter.model == "switching" and sc.inverter.dead_time_s == 2e-6
    assert sc.inverter.device_drop_V == 1.0 and sc.control.delay_periods == 1
    assert sc.sensor.adc_bits == 12 and sc.sensor.noise_rms_A == 0.02
    assert sc.plant.saturation.enabled
    # a commissioned controller: the tables the documented procedure gives (not stale)
    cm = sc.controller_model
    assert cm.uses_magnetising_curve and cm.uses_inverter_error
    tables = ideal_commissioning(sc)
    for key, values in tables.items():
        assert getattr(cm, key) == pytest.approx(values, rel=1e-12), key


def test_the_uncommissioned_realistic_preset_keeps_the_constant_model():
    sc = Scenario.read("sensorless-realistic-uncommissioned")
    assert not sc.controller_model.uses_magnetising_curve
    assert not sc.controller_model.uses_inverter_error
    assert sc.control.dead_time_compensation_s == pytest.approx(1.6e-6)
    assert sc.plant.saturation.enabled and sc.inverter.dead_time_s == 2e-6


def test_batch_and_sweeps_run_the_realistic_drive_bit_identical_to_single_runs():
    from imdrive.run.batch import simulate_batch

    scs = [
        Scenario.read("sensorless-realistic", ["simulation.t_end_s=0.4", "simulation.log_every=1"]),
        Scenario.read(
            "sensorless-realistic",
            ["simulation.t_end_s=0.4", "simulation.log_every=1", "sensor.seed=7"],
        ),
    ]
    batch = simulate_batch(scs, logs=True)
    for sc, many in zip(scs, batch.results, strict=True):
        one = simulate(sc)
        for name, v in one.signals.items():
            assert np.array_equal(many.signals[name], v), name
        assert np.array_equal(many.c_final, one.c_final)


def _saturated_rhs(m, curve):
    """The saturated machine written here: currents from the fluxes through the magnetising
    curve, solved by Newton's method to machine precision at every evaluation."""
    Ll1, Ll2 = m.Ll1_H, m.Ll2_H
    Lm0, psi_sat, S = curve["Lm0"], curve["psi_sat"], curve["S"]
    G = 1 / Ll1 + 1 / Ll2

    def currents(y):
        x = y[0:2] / Ll1 + y[2:4] / Ll2
        X = np.hypot(*x)
        if X == 0.0:
            return y[0:2] / Ll1, y[2:4] / Ll2
        mm = X / (G + 1 / Lm0)
        for _ in range(100):
            r = (mm / psi_sat) ** S
            step = (G * mm + mm / Lm0 * (1 + r) - X) / (G + (1 + (S + 1) * r) / Lm0)
            mm -= step
            if abs(step) <= 1e-16 * mm:
                break
        pm = mm / X * x
        return (y[0:2] - pm) / Ll1, (y[2:4] - pm) / Ll2

    def rhs(t, y, va, vb):
        i_s, i_r = currents(y)
        w_r = m.pole_pairs * y[4]
        dps = np.array([va, vb]) - m.R1_ohm * i_s
        dpr = -m.R2_ohm * i_r + w_r * np.array([-y[3], y[2]])
        Te = 1.5 * m.pole_pairs * (y[0] * i_s[1] - y[1] * i_s[0])
        return np.concatenate([dps, dpr, [Te / m.J_kgm2]])

    return rhs, currents


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@pytest.mark.parametrize("V_ll", [220.0, 270.0])
def test_saturated_switching_matches_solve_ivp_with_switching_instants_as_breakpoints(V_ll):
    """Saturation on the switching bridge: the inrush from standstill (the flux's DC offset
    drives the machine to about twice its rated flux, deep into the curve) against solve_ivp
    on a saturated machine written here, the switching instants as breakpoints."""
    from imdrive.run.build import saturation_curve

    sc = _sc(
        "free-acceleration",
        "inverter.model=switching",
        "inverter.Vdc_V=400",
        "plant.saturation.enabled=true",
        f"open_loop.voltage_V={V_ll}",
        "simulation.t_end_s=0.02",
    )
    res = simulate(sc)
    m = sc.machine
    Ts, Vdc = sc.simulation.Ts_s, sc.inverter.Vdc_V
    rhs, currents = _saturated_rhs(m, saturation_curve(sc))
    y = np.zeros(5)
    i_ref = [np.zeros(2)]
    for k in range(sc.simulation.n_steps):
        va, vb = res["v_ref_alpha_V"][k], res["v_ref_beta_V"][k]
        for t0, t1, sa, sb in _svpwm_segments(va, vb, Vdc, Ts):
            sol = solve_ivp(
                rhs, (t0, t1), y, method="DOP853", rtol=1e-11, atol=1e-12, args=(sa, sb)
            )
            y = sol.y[:, -1]
        i_ref.append(currents(y)[0])
    i_ref = np.array(i_ref)
    got = np.column_stack([res["i_alpha_A"], res["i_beta_A"]])
    assert np.max(np.abs(i_ref)) > 50.0
    err = np.max(np.abs(got - i_ref))
    assert err <= 1e-4, err


@pytest.mark.slow  # 1.5 s or more on 2 cores (2026-11-28)
@pytest.mark.parametrize("V_ll", [220.0, 270.0])
def test_saturated_dead_time_matches_solve_ivp(V_ll):
    """Saturation with dead time and device drops (the short intervals between a gate command
    and its delayed transition hold the magnetising ratio of their start): the inrush from
    standstill deep into the curve against solve_ivp on the saturated machine written here,
    the bridge's events as breakpoints."""
    from imdrive.run.build import saturation_curve

    t_d, drop = 2e-6, 1.0
    sc = _sc(
        "free-acceleration",
        "inverter.model=switching",
        "inverter.Vdc_V=400",
        f"inverter.dead_time_s={t_d}",
        f"inverter.device_drop_V={drop}",
        "plant.saturation.enabled=true",
        f"open_loop.voltage_V={V_ll}",
        "simulation.t_end_s=0.02",
    )
    res = simulate(sc)
    rhs, currents = _saturated_rhs(sc.machine, saturation_curve(sc))
    i_ref = _dead_time_reference(sc, res, rhs, lambda y: currents(y)[0], t_d, drop)
    got = np.column_stack([res["i_alpha_A"], res["i_beta_A"]])
    assert np.max(np.abs(i_ref)) > 50.0
    err = np.max(np.abs(got - i_ref))
    assert err <= 1e-4, err


def test_saturation_table_error_bound():
    """The run's table of the inverse magnetising curve (one Newton correction after a cubic
    Hermite interpolation, no loop) against Newton's method to convergence: relative error
    of ``k = |psi_m|/|psi_x|`` within ``SAT_TABLE_TOL`` over the table and beyond it."""
    from imdrive.kernels.machine import SAT_TABLE_TOL, magnetising_ratio
    from imdrive.run.build import saturation_curve

    sc = Scenario.read("sensorless-realistic")
    p = build_arrays(sc).params.plant[0]
    assert p["sat_X_max"] > 0.0  # the default curve is tabulated
    curve = saturation_curve(sc)
    _, currents = _saturated_rhs(sc.machine, curve)
    Ll1, Ll2 = sc.machine.Ll1_H, sc.machine.Ll2_H
    worst = 0.0
    for X in np.linspace(1e-3, 1.5 * p["sat_X_max"], 3001):
        k, _ = magnetising_ratio(p, X)
        y = np.array([X * Ll1, 0.0, 0.0, 0.0])  # psi_x = X along alpha
        i_s, _ = currents(y)
        k_ref = (y[0] - Ll1 * i_s[0]) / X
        worst = max(worst, abs(k / k_ref - 1.0))
    assert worst <= SAT_TABLE_TOL, worst
    # a curve too sharp for the grid is not tabulated (the full solve is used instead)
    from imdrive.kernels.machine import saturation_table

    sharp = saturation_table(Ll1, Ll2, curve["Lm0"], curve["psi_sat"], 50.0)
    assert sharp["sat_X_max"] == 0.0 or sharp["sat_table_error"] <= SAT_TABLE_TOL
