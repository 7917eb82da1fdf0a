"""The commissioned controller: a saturation-aware flux model and the inverter-error table.

Checked against things computed here, independently of the kernels: the saturated machine's
phasor steady state solved by scipy (fsolve) from the plant's own magnetising curve, the
plant's incremental inductance by differentiation of that curve, and the average inverter's
dead-time law.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import fsolve

from imdrive.analysis.commissioning import (
    ideal_commissioning,
    plant_magnetising_curve,
    plant_secant_inductance,
)
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.kernels.ifoc import dead_time_feedforward
from imdrive.kernels.inverter import MAX_SEGMENTS, inverter_segments
from imdrive.kernels.model import magnetising_inductances, reference_magnetising
from imdrive.run.build import build_arrays
from imdrive.run.simulate import simulate

MACHINES = ("paper-table-iv", "aalto-2.2kw")


def _with_tables(preset_overrides: list[str], base: str = "vector-sensored") -> Scenario:
    sc = Scenario.read(base, preset_overrides)
    tables = ideal_commissioning(sc)
    text = [f"controller_model.{k}=[{', '.join(map(repr, v))}]" for k, v in tables.items()]
    return Scenario.read(base, [*preset_overrides, *text])


# --------------------------------------------------------------------------------------------
# the section's rules


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        (["magnetising_psi_Wb=[0.1, 0.2]"], "magnetising_Lm_H"),
        (["magnetising_psi_Wb=[0.1]", "magnetising_Lm_H=[0.07]"], "magnetising_psi_Wb"),
        (["magnetising_psi_Wb=[0.2, 0.1]", "magnetising_Lm_H=[0.07, 0.07]"], "magnetising_psi_Wb"),
        (["magnetising_psi_Wb=[0.1, 0.2]", "magnetising_Lm_H=[0.07, -0.07]"], "magnetising_Lm_H"),
        (["inverter_error_i_A=[0.0, 1.0]"], "inverter_error_u_V"),
        (["inverter_error_i_A=[0.5, 1.0]", "inverter_error_u_V=[1.0, 1.0]"], "inverter_error_i_A"),
        (
            ["inverter_error_i_A=[-1.0, 0.0, 2.0]", "inverter_error_u_V=[-1.0, 0.0, 1.0]"],
            "inverter_error_i_A",
        ),
        (["inverter_error_i_A=[0.0, 1.0]", "inverter_error_u_V=[0.0, -1.0]"], "inverter_error_u_V"),
    ],
)
def test_bad_tables_are_refused_in_one_line_naming_the_field(overrides, field):
    with pytest.raises(ConfigError) as exc:
        Scenario.read("sensorless", [f"controller_model.{o}" for o in overrides])
    msg = str(exc.value)
    assert f"controller_model.{field}" in msg and "\n" not in msg


def test_an_odd_table_over_both_signs_is_its_half_from_zero():
    both = Scenario.read(
        "sensorless",
        [
            "controller_model.inverter_error_i_A=[-2.0, -0.2, 0.0, 0.2, 2.0]",
            "controller_model.inverter_error_u_V=[-7.0, -6.0, 0.0, 6.0, 7.0]",
        ],
    )
    half = Scenario.read(
        "sensorless",
        [
            "controller_model.inverter_error_i_A=[0.0, 0.2, 2.0]",
            "controller_model.inverter_error_u_V=[0.0, 6.0, 7.0]",
        ],
    )
    a, b = build_arrays(both).params.control[0], build_arrays(half).params.control[0]
    assert a["ie_n"] == b["ie_n"] == 3
    assert np.array_equal(a["ie_i"], b["ie_i"]) and np.array_equal(a["ie_u"], b["ie_u"])
    assert dead_time_feedforward(a, -1.1, 0.3) == dead_time_feedforward(b, -1.1, 0.3)


def test_a_curve_whose_current_falls_with_the_flux_is_refused():
    with pytest.raises(ConfigError, match="monotone"):
        Scenario.read(
            "sensorless",
            [
                "controller_model.magnetising_psi_Wb=[0.2, 0.4]",
                "controller_model.magnetising_Lm_H=[0.05, 0.2]",
            ],
        )


def test_empty_tables_keep_the_constant_model():
    sc = Scenario.read("sensorless")
    arr = build_arrays(sc)
    assert arr.state0.model[0]["sat_n"] == 0 and arr.params.control[0]["ie_n"] == 0


# --------------------------------------------------------------------------------------------
# the table


@pytest.mark.parametrize("machine", MACHINES)
def test_table_exact_at_the_nodes_and_incremental_inductance_of_the_plant(machine):
    sc = _with_tables([f'machine.preset="{machine}"', "plant.saturation.enabled=true"])
    m = build_arrays(sc).state0.model[0]
    psi = np.array(sc.controller_model.magnetising_psi_Wb)
    Lm = np.array(sc.controller_model.magnetising_Lm_H)
    for p, L in zip(psi, Lm, strict=True):
        got, _ = magnetising_inductances(m, p)
        assert got == pytest.approx(L, rel=1e-12)
    # between the nodes: the plant's secant and incremental inductances (0.3-1.2 rated flux)
    Lm0, psi_sat, S = plant_magnetising_curve(sc)
    for p in np.linspace(0.3, 1.2, 37) * sc.machine.rated_flux_Wb:
        sec, inc = magnetising_inductances(m, p)
        r = (p / psi_sat) ** S
        assert sec == pytest.approx(Lm0 / (1 + r), rel=2e-4)
        assert inc == pytest.approx(Lm0 / (1 + (S + 1) * r), rel=1e-2)


# --------------------------------------------------------------------------------------------
# the flux at its reference: phasor steady state of the saturated machine


def _plant_flux(sc: Scenario, i_d: float, i_q: float, w_sl: float) -> complex:
    """Rotor flux (controller's frame) of the saturated plant fed ``i_d + j i_q`` at slip
    ``w_sl``: ``0 = R2 i_r + j w_sl psi_r``, ``psi_r = psi_m + Ll2 i_r``,
    ``psi_m = Lm(|psi_m|)(i_s + i_r)``, solved by fsolve."""
    m = sc.machine
    i_s = complex(i_d, i_q)

    def eqs(x):
        i_r = complex(x[0], x[1])
        pm = complex(x[2], x[3])
        Lm = float(plant_secant_inductance(sc, abs(pm)))
        r1 = pm - Lm * (i_s + i_r)
        r2 = m.R2_ohm * i_r + 1j * w_sl * (pm + m.Ll2_H * i_r)
        return [r1.real, r1.imag, r2.real, r2.imag]

    x0 = [0.0, -i_q * m.M_H / (m.M_H + m.Ll2_H), m.M_H * i_d, 0.0]
    x = fsolve(eqs, x0, xtol=1e-12)
    assert np.max(np.abs(eqs(x))) < 1e-10  # solved (to rounding: fsolve's flag is stricter)
    return complex(x[2], x[3]) + m.Ll2_H * complex(x[0], x[1])


def _ifoc_steady_state(sc: Scenario, psi_ref: float, i_q: float) -> tuple[float, float]:
    """The controller's id* and slip in steady state at ``psi_ref``, ``i_q``: the kernels'
    own functions on the built model, iterated as the loop does period after period."""
    m = build_arrays(sc).state0.model[0]
    Ll2 = m["Ll2_hat"]
    for _ in range(200):  # the per-period fixed point of update_magnetising, to convergence
        M_ref = reference_magnetising(m, psi_ref, i_q)
        i_d = psi_ref / M_ref
        k = m["M_hat"] / (Ll2 + m["M_hat"])
        psi_m = math.hypot(k * (psi_ref + Ll2 * i_d), k * Ll2 * i_q)
        if m["sat_n"] > 0:
            m["M_hat"], _ = magnetising_inductances(m, psi_m)
    M = m["M_hat"]
    w_sl = M * m["R2_hat"] / (Ll2 + M) * i_q / psi_ref
    return i_d, w_sl


@pytest.mark.parametrize("machine", MACHINES)
@pytest.mark.parametrize("flux_pu", [0.6, 1.0, 1.15])
@pytest.mark.parametrize("load_pu", [0.0, 1.0, -1.0])
def test_ifoc_flux_at_its_reference_in_steady_state_with_the_true_curve(machine, flux_pu, load_pu):
    base = [f'machine.preset="{machine}"', "plant.saturation.enabled=true"]
    sc = _with_tables(base)
    psi_ref = flux_pu * sc.machine.rated_flux_Wb
    i_q = load_pu * sc.machine.rated_current_A * math.sqrt(2.0) * 0.8
    i_d, w_sl = _ifoc_steady_state(sc, psi_ref, i_q)
    psi_r = _plant_flux(sc, i_d, i_q, w_sl)
    assert abs(psi_r) == pytest.approx(psi_ref, rel=2e-4)
    assert abs(math.atan2(psi_r.imag, psi_r.real)) < 2e-4  # oriented on the d axis
    # the constant model misses the reference away from the rated flux
    if flux_pu != 1.0:
        i_d0, w_sl0 = _ifoc_steady_state(Scenario.read("vector-sensored", base), psi_ref, i_q)
        assert abs(abs(_plant_flux(sc, i_d0, i_q, w_sl0)) / psi_ref - 1.0) > 5e-3


@pytest.mark.slow
def test_closed_loop_flux_at_its_reference_with_saturation_on():
    """The sensored drive at 1.15 rated flux and rated load on the saturated plant: with the
    commissioned curve the plant's rotor flux settles at the reference; with the constant
    M_hat it does not."""
    base = [
        'machine.preset="paper-table-iv"',
        "plant.saturation.enabled=true",
        "control.flux_ref_Wb=0.5326",
        "simulation.t_end_s=3.0",
        "output.figures=false",
    ]
    fluxes = []
    for sc in (_with_tables(base), Scenario.read("vector-sensored", base)):
        res = simulate(sc)
        late = res["time_s"] > 2.7
        fluxes.append(np.mean(res["flux_Wb"][late]))
    assert fluxes[0] == pytest.approx(0.5326, rel=2e-3)
    assert abs(fluxes[1] / 0.5326 - 1.0) > 1e-2


# --------------------------------------------------------------------------------------------
# the inverter-error table


@pytest.mark.parametrize("machine", MACHINES)
def test_table_feedforward_cancels_the_average_inverters_error(machine):
    """Average inverter (dead time, device drop, smooth sign over sign_band_A): the ideal
    table's feed-forward makes the applied voltage the reference, for any current."""
    over = [
        f'machine.preset="{machine}"',
        "inverter.dead_time_s=2e-6",
        "inverter.device_drop_V=1.0",
        "inverter.sign_band_A=0.2",
    ]
    sc = _with_tables(over)
    arr = build_arrays(sc)
    pinv, pc = arr.params.inverter[0], arr.params.control[0]
    uncomp = Scenario.read(
        "vector-sensored",
        [
            *over,
            'control.dead_time_compensation="feedforward"',
            "control.dead_time_compensation_s=1.6e-6",
        ],
    )
    pc0 = build_arrays(uncomp).params.control[0]
    Ts = sc.simulation.Ts_s
    seg = np.zeros((3, MAX_SEGMENTS))
    rng = np.random.default_rng(3)
    worst = worst0 = 0.0
    for _ in range(200):
        i = complex(*rng.normal(0.0, 4.0, 2))
        v = complex(*rng.normal(0.0, 30.0, 2))  # inside the linear range
        for p, store in ((pc, 0), (pc0, 1)):
            dv = dead_time_feedforward(p, i.real, i.imag)
            n = inverter_segments(
                pinv, v.real + dv[0], v.imag + dv[1], i.real, i.imag, Ts, seg[0], seg[1], seg[2]
            )
            app = complex(np.dot(seg[0, :n], seg[1, :n]), np.dot(seg[0, :n], seg[2, :n])) / Ts
            if store == 0:
                worst = max(worst, abs(app - v))
            else:
                worst0 = max(worst0, abs(app - v))
    u = pc["ie_u"][1]
    assert worst < 1e-5 * u  # the table's 6 significant digits
    assert worst0 > 0.5  # the uncommissioned sign model: 20 % of the dead time's loss left


def test_table_feedforward_on_the_switching_bridge():
    """Switching bridge, open-loop at 5 Hz: the voltage the estimators believe applied (the
    commanded less the table's feed-forward) against the period average the bridge applied;
    the table removes the dead time's error down to the ripple's share near the current's
    zero crossings."""
    over = [
        "inverter.model=switching",
        "inverter.dead_time_s=2e-6",
        "inverter.device_drop_V=1.0",
        "simulation.Ts_s=1e-4",
        "inverter.switching_frequency_Hz=1e4",
        "open_loop.voltage_V=20",
        "open_loop.frequency_Hz=5",
        "simulation.t_end_s=1.0",
        "simulation.log_every=1",
        "output.figures=false",
    ]
    errors = []
    for sc in (_with_tables(over, "free-acceleration"), Scenario.read("free-acceleration", over)):
        res = simulate(sc)
        arr = build_arrays(sc)
        pc = arr.params.control[0]
        late = res["time_s"] > 0.6
        ia, ib = res["i_alpha_meas_A"][late], res["i_beta_meas_A"][late]
        dv = np.array([dead_time_feedforward(pc, a, b) for a, b in zip(ia, ib, strict=True)])
        believed = res["v_ref_alpha_V"][late] - dv[:, 0]
        # the applied average of period k is logged at sample k; no computation delay
        errors.append(np.sqrt(np.mean((res["v_alpha_V"][late] - believed) ** 2)))
    u = ideal_commissioning(Scenario.read("free-acceleration", over))["inverter_error_u_V"][1]
    assert errors[1] > 0.5 * u  # uncompensated: the whole error (about 4/3 u rms in alpha)
    assert errors[0] < 0.2 * errors[1]


def test_table_feedforward_acts_at_the_current_of_the_period_where_the_voltage_acts():
    """The table's feed-forward takes the phase errors at the measured current turned by the
    controller's frequency over angle_advance periods (1.5 with the one-period delay)."""
    from imdrive.kernels.ifoc import CONTROL_STATE, inverter_feedforward

    sc = _with_tables(["control.delay_periods=1", "inverter.dead_time_s=2e-6"])
    pc = build_arrays(sc).params.control[0]
    assert pc["angle_advance"] == 1.5
    s = np.zeros(1, dtype=CONTROL_STATE)[0]
    s["w_e"] = 2 * math.pi * 50.0
    Ts = sc.simulation.Ts_s
    i = complex(0.05, 3.0)  # phase a's current near its zero crossing
    turned = i * complex(math.cos(s["w_e"] * 1.5 * Ts), math.sin(s["w_e"] * 1.5 * Ts))
    got = inverter_feedforward(pc, s, i.real, i.imag, Ts)
    assert got == dead_time_feedforward(pc, turned.real, turned.imag)
    assert got != dead_time_feedforward(pc, i.real, i.imag)  # the sign of phase a changed
    # the switching bridge's sign model of [control] is turned the same way
    sign = Scenario.read("sensorless-realistic-uncommissioned")
    pc0 = build_arrays(sign).params.control[0]
    assert pc0["dtc_ripple"] > 0.0 and pc0["dtc_u"] > 0.0
    assert inverter_feedforward(pc0, s, i.real, i.imag, Ts) == dead_time_feedforward(
        pc0, turned.real, turned.imag
    )
    # the fixed band's is not (as the average model's: its loss acts at the sample's current)
    fixed = Scenario.read(
        "sensorless-realistic-uncommissioned", ['control.dead_time_compensation_band="fixed"']
    )
    pc1 = build_arrays(fixed).params.control[0]
    assert pc1["dtc_ripple"] == 0.0
    assert inverter_feedforward(pc1, s, i.real, i.imag, Ts) == dead_time_feedforward(
        pc1, i.real, i.imag
    )


def test_injection_sensitivity_on_the_saturation_aware_model():
    """The compensator's input scale M S(T2) / (L_inc S(T2_inc)) at rated flux, against the
    plant's curve differentiated here; 1 on the constant model."""
    from imdrive.kernels.compensator import in_phase_sensitivity, saturation_sensitivity_ratio

    sc = _with_tables([], "injection-fig5-realistic")
    arr = build_arrays(sc)
    pk, s, m = arr.params.comp[0], arr.state0.comp[0], arr.state0.model[0]
    psi = sc.machine.rated_flux_Wb
    m["M_hat"], m["L_inc_hat"] = magnetising_inductances(m, psi)
    Lm0, psi_sat, S = plant_magnetising_curve(sc)
    r = (psi / psi_sat) ** S
    M, L_inc = Lm0 / (1 + r), Lm0 / (1 + (S + 1) * r)
    R2, Ll2, w = m["R2_hat"], m["Ll2_hat"], 2 * math.pi * pk["inj_freq"]

    def ratio(M, L_inc):
        want = M * in_phase_sensitivity(w, (Ll2 + M) / R2)
        return want / (L_inc * in_phase_sensitivity(w, (Ll2 + L_inc) / R2))

    got = saturation_sensitivity_ratio(pk, s, m)
    assert got == pytest.approx(ratio(m["M_hat"], m["L_inc_hat"]), rel=1e-12)  # the formula
    # against the plant's own curve: the table's L_inc is within 1 % (tested above), the ratio
    # moves about twice as much as L_inc (its gain and its time constant)
    assert got == pytest.approx(ratio(M, L_inc), rel=3e-2)
    assert ratio(M, L_inc) > 2.0  # the unscaled signal: under half the constant model's
    m0 = build_arrays(Scenario.read("injection-fig5")).state0.model[0]
    assert saturation_sensitivity_ratio(pk, s, m0) == 1.0
