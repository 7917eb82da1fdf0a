"""Tests of imdrive.analysis: equivalent circuit, breakdown torque, field-oriented steady state."""

import cmath
import math
import warnings

import numpy as np
import pytest
from matplotlib.figure import Figure

from imdrive.analysis import (
    breakdown,
    breakdown_thevenin,
    detuning_speed_error_rpm,
    equivalent_circuit,
    foc_operating_point,
    plot_speed_error_vs_R2,
)
from imdrive.config.machine import machine_preset
from imdrive.errors import ConfigError


@pytest.fixture(scope="module")
def m():
    return machine_preset("paper-table-iv")


SLIPS = np.array([-0.3, -0.02, 0.0, 1e-4, 0.01, 0.05, 0.2, 0.527, 1.0, 1.5])


# ------------------------------------------------------------------------------------------
# equivalent circuit


def test_power_balance(m):
    ss = equivalent_circuit(m, 220.0, 60.0, SLIPS)
    losses_and_work = ss.P_cu1_W + ss.P_cu2_W + ss.torque_Nm * ss.w_m
    np.testing.assert_allclose(ss.P_in_W, losses_and_work, rtol=1e-9, atol=1e-9)
    # rotor copper = s * air-gap power, mechanical = (1 - s) * air-gap power
    np.testing.assert_allclose(ss.P_cu2_W, SLIPS * ss.P_airgap_W, rtol=1e-9, atol=1e-9)


def test_torque_three_ways(m):
    ss = equivalent_circuit(m, 220.0, 60.0, SLIPS)
    n_p, w_e = m.pole_pairs, 2 * math.pi * 60.0
    # (1) from the air-gap power measured at the terminals: P_in - P_cu1
    T_airgap = (ss.P_in_W - ss.P_cu1_W) * n_p / w_e
    np.testing.assert_allclose(ss.torque_Nm, T_airgap, rtol=1e-9, atol=1e-9)
    # (2) from the rotor current, 1.5 n_p |I2|^2 R2 / (s w_e), where s != 0
    nz = SLIPS != 0
    T_rotor = 1.5 * n_p * np.abs(ss.I2[nz]) ** 2 * m.R2_ohm / (SLIPS[nz] * w_e)
    np.testing.assert_allclose(ss.torque_Nm[nz], T_rotor, rtol=1e-12)
    # (3) from the flux cross product 1.5 n_p Im(psi_s* i_s), as in the plant model
    psi_s = m.L1_H * ss.I1 + m.M_H * ss.I2
    T_cross = 1.5 * n_p * np.imag(np.conj(psi_s) * ss.I1)
    np.testing.assert_allclose(ss.torque_Nm, T_cross, rtol=1e-9, atol=1e-9)
    # and the rotor flux is what the FOC formula uses: T = 1.5 n_p (M/L2) Im(psi_r* i_s)
    psi_r = m.M_H * ss.I1 + m.L2_H * ss.I2
    np.testing.assert_allclose(ss.psi_r_Wb, np.abs(psi_r), rtol=1e-12)
    T_rot = 1.5 * n_p * m.M_H / m.L2_H * np.imag(np.conj(psi_r) * ss.I1)
    np.testing.assert_allclose(ss.torque_Nm, T_rot, rtol=1e-9, atol=1e-9)


def test_krause_hand_calculation(m):
    # Krause's 3 hp machine at s = 0.05, per-phase RMS textbook circuit, written out by hand:
    # X = 2 pi 60 L, V_phase = 220/sqrt(3) rms, T = 3 (P/2) |I2'|^2 (R2/s) / w_e.
    s = 0.05
    w = 2 * math.pi * 60.0
    X1, X2, XM = w * 0.002, w * 0.002, w * 0.0693
    R1, R2 = 0.435, 0.816
    V = 220.0 / math.sqrt(3.0)
    Z2 = complex(R2 / s, X2)
    Zm = complex(0.0, XM)
    Z = complex(R1, X1) + Zm * Z2 / (Zm + Z2)
    I1 = V / Z
    I2p = I1 * Zm / (Zm + Z2)  # flows out of the magnetising node into the rotor branch
    T = 3 * 2 * abs(I2p) ** 2 * (R2 / s) / w
    pf = math.cos(-cmath.phase(I1))

    ss = equivalent_circuit(m, 220.0, 60.0, s)
    assert ss.I1_rms_A == pytest.approx(abs(I1), rel=1e-12)
    assert ss.I1_peak_A == pytest.approx(math.sqrt(2) * abs(I1), rel=1e-12)
    assert ss.I2_rms_A == pytest.approx(abs(I2p), rel=1e-12)
    assert ss.torque_Nm == pytest.approx(T, rel=1e-12)
    assert ss.power_factor == pytest.approx(pf, rel=1e-12)
    assert ss.speed_rpm == pytest.approx(1710.0, rel=1e-12)
    # peak phasors: I1 (peak) = sqrt(2) * I1 (rms), same angle; I2 = -I2'
    assert ss.I1 == pytest.approx(math.sqrt(2) * I1, rel=1e-12)
    assert ss.I2 == pytest.approx(-math.sqrt(2) * I2p, rel=1e-12)
    # the numbers themselves (near the 3 hp rating: 2238 W / 179 rad/s = 12.5 N m)
    assert T == pytest.approx(14.03, abs=0.01)
    assert abs(I1) == pytest.approx(8.85, abs=0.01)


def test_no_load_current_and_zero_slip(m):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no division-by-zero warnings at s = 0
        ss = equivalent_circuit(m, 220.0, 60.0, 0.0)
    w_e = 2 * math.pi * 60.0
    V = math.sqrt(2.0 / 3.0) * 220.0
    assert ss.I1 == pytest.approx(V / complex(m.R1_ohm, w_e * m.L1_H), rel=1e-14)
    assert ss.torque_Nm == 0.0
    assert ss.I2 == 0.0
    assert ss.speed_rpm == pytest.approx(1800.0, rel=1e-14)
    # a tiny slip is continuous with s = 0
    tiny = equivalent_circuit(m, 220.0, 60.0, 1e-12)
    assert tiny.I1 == pytest.approx(ss.I1, rel=1e-9)
    # at no load psi_r = M |I1|; MachineParams.rated_flux_Wb is the same with R1 neglected
    assert ss.psi_r_Wb == pytest.approx(m.M_H * abs(ss.I1), rel=1e-14)
    assert ss.psi_r_Wb == pytest.approx(m.rated_flux_Wb, rel=1e-3)
    assert ss.psi_r_Wb < m.rated_flux_Wb


def test_broadcasting(m):
    ss = equivalent_circuit(m, np.array([[110.0], [220.0]]), 60.0, np.linspace(0, 1, 5))
    assert ss.torque_Nm.shape == (2, 5)
    # torque scales with V^2 at fixed frequency and slip
    np.testing.assert_allclose(ss.torque_Nm[1], 4 * ss.torque_Nm[0], rtol=1e-12)
    scalar = equivalent_circuit(m, 220.0, 60.0, 0.05)
    assert isinstance(scalar.torque_Nm, float)
    assert isinstance(scalar.I1, complex)


def test_bad_inputs(m):
    with pytest.raises(ConfigError):
        equivalent_circuit(m, 220.0, 0.0, 0.05)
    with pytest.raises(ConfigError):
        equivalent_circuit(m, -1.0, 60.0, 0.05)
    with pytest.raises(ConfigError):
        foc_operating_point(m, 1500.0, 12.0, R2_ratio=0.0)


# ------------------------------------------------------------------------------------------
# breakdown


@pytest.mark.parametrize("V, f", [(220.0, 60.0), (110.0, 30.0), (40.0, 5.0)])
def test_breakdown_numeric_vs_thevenin(m, V, f):
    s_num, T_num = breakdown(m, V, f)
    s_th, T_th = breakdown_thevenin(m, V, f)
    assert s_num == pytest.approx(s_th, rel=1e-6)
    assert T_num == pytest.approx(T_th, rel=1e-9)
    # the closed form is exact: the circuit gives exactly T_th at s_th (catches wrong factors)
    assert equivalent_circuit(m, V, f, s_th).torque_Nm == pytest.approx(T_th, rel=1e-12)
    # and it is a maximum
    for ds in (-1e-3, 1e-3):
        assert equivalent_circuit(m, V, f, s_th * (1 + ds)).torque_Nm < T_th


def test_breakdown_value(m):
    s_bd, T_bd = breakdown(m, 220.0, 60.0)
    assert s_bd == pytest.approx(0.5268, abs=1e-4)
    assert T_bd == pytest.approx(61.87, abs=0.01)


# ------------------------------------------------------------------------------------------
# field-oriented steady state


def test_sensorless_detuning_law_sign_and_size(m):
    ref = foc_operating_point(m, 1500.0, 12.0, R2_ratio=1.0)
    assert ref.speed_error_rpm == pytest.approx(0.0, abs=1e-9)
    hi = foc_operating_point(m, 1500.0, 12.0, R2_ratio=1.2)
    lo = foc_operating_point(m, 1500.0, 12.0, R2_ratio=0.8)
    # overestimated R2 with a motoring load: the true machine runs faster than the reference
    assert hi.speed_error_rpm > 0
    assert lo.speed_error_rpm < 0
    assert hi.speed_error_rpm == pytest.approx(0.2 * hi.slip_mech_rpm, rel=1e-12)
    assert lo.speed_error_rpm == pytest.approx(-0.2 * lo.slip_mech_rpm, rel=1e-12)
    assert hi.speed_est_rpm == pytest.approx(1500.0, rel=1e-14)
    # the true slip does not depend on R2_hat: it is the correctly tuned one
    assert hi.slip_mech_rpm == pytest.approx(ref.slip_mech_rpm, rel=1e-12)
    # generating load: the sign flips
    gen = foc_operating_point(m, 1500.0, -12.0, R2_ratio=1.2)
    assert gen.speed_error_rpm < 0
    err = detuning_speed_error_rpm(m, 1500.0, 12.0, [0.8, 1.0, 1.2])
    np.testing.assert_allclose(
        err, [lo.speed_error_rpm, 0.0, hi.speed_error_rpm], rtol=1e-12, atol=1e-9
    )


@pytest.mark.parametrize("k", [0.8, 1.0, 1.2, 1.5])
def test_sensorless_orientation_and_mras_equilibrium(m, k):
    op = foc_operating_point(m, 600.0, 10.0, R2_ratio=k)
    # orientation correct: flux = reference on the d axis, torque = load
    assert op.torque_Nm == pytest.approx(10.0, rel=1e-12)
    assert op.psi_r_Wb == pytest.approx(m.rated_flux_Wb, rel=1e-12)
    assert abs(op.orientation_error_rad) < 1e-12
    # the MRAS equilibrium, from the two models' steady states in the synchronous frame:
    # reference model = true flux M I/(1 + j (w_e - w_r) T2), adjustable model uses R2_hat and
    # the estimated speed. They must coincide (e = 0), which is what the law rests on.
    I = complex(op.id_A, op.iq_A)
    w_r = m.pole_pairs * op.w_m
    w_r_hat = m.pole_pairs * op.speed_est_rpm * math.pi / 30.0
    T2 = m.L2_H / m.R2_ohm
    T2_hat = T2 / k
    psi_true = m.M_H * I / complex(1.0, (op.w_e - w_r) * T2)
    psi_hat = m.M_H * I / complex(1.0, (op.w_e - w_r_hat) * T2_hat)
    assert abs(psi_hat - psi_true) < 1e-12 * abs(psi_true)
    # IFOC frequency: w_e = w_r_hat + (R2_hat/L2) iq/id
    assert op.w_e == pytest.approx(w_r_hat + k * op.iq_A / (op.id_A * T2), rel=1e-12)


@pytest.mark.parametrize("sensorless", [True, False])
@pytest.mark.parametrize("k", [0.8, 1.2])
def test_foc_consistent_with_equivalent_circuit(m, sensorless, k):
    # the same operating point seen as a sinusoidal supply: V, f, slip from the FOC solution
    op = foc_operating_point(m, 900.0, 12.0, R2_ratio=k, sensorless=sensorless)
    ss = equivalent_circuit(m, op.V_ll_rms_V, op.f_Hz, op.slip)
    assert ss.torque_Nm == pytest.approx(op.torque_Nm, rel=1e-9)
    assert ss.I1_peak_A == pytest.approx(op.is_peak_A, rel=1e-9)
    assert ss.psi_r_Wb == pytest.approx(op.psi_r_Wb, rel=1e-9)
    assert ss.w_m == pytest.approx(op.w_m, rel=1e-12)


def test_measured_speed_detuned_flux(m):
    tuned = foc_operating_point(m, 1500.0, 12.0, R2_ratio=1.0, sensorless=False)
    assert tuned.psi_r_Wb == pytest.approx(m.rated_flux_Wb, rel=1e-12)
    assert tuned.speed_error_rpm == 0.0
    same = foc_operating_point(m, 1500.0, 12.0, R2_ratio=1.0, sensorless=True)
    assert tuned.iq_A == pytest.approx(same.iq_A, rel=1e-12)
    assert tuned.V_s_peak_V == pytest.approx(same.V_s_peak_V, rel=1e-12)

    over = foc_operating_point(m, 1500.0, 12.0, R2_ratio=1.2, sensorless=False)
    under = foc_operating_point(m, 1500.0, 12.0, R2_ratio=0.8, sensorless=False)
    for op in (over, under):
        assert op.torque_Nm == pytest.approx(12.0, rel=1e-12)
        assert op.speed_rpm == pytest.approx(1500.0, rel=1e-14)
    # R2_hat > R2: the controller imposes a slip k times too large for its currents, so
    # w_sl T2 = k iq/id and |psi_r| = M id sqrt((1 + x^2)/(1 + k^2 x^2)) < M id: more of the
    # magnetising current is cancelled by the rotor current, the flux sags and the speed loop
    # compensates with a larger iq.
    assert over.psi_r_Wb < over.flux_ref_Wb
    assert over.iq_A > tuned.iq_A
    # R2_hat < R2: the opposite (flux above the reference, linear magnetics)
    assert under.psi_r_Wb > under.flux_ref_Wb
    # detuning also rotates the flux out of the d axis, in the opposite sense for k > 1 and k < 1
    assert over.orientation_error_rad < 0 < under.orientation_error_rad
    # without load there is no slip and the detuning is invisible
    idle = foc_operating_point(m, 1500.0, 0.0, R2_ratio=1.2, sensorless=False)
    assert idle.psi_r_Wb == pytest.approx(m.rated_flux_Wb, rel=1e-12)


def test_friction_in_torque_balance(m):
    mb = m.with_(B_Nms=0.01)
    op = foc_operating_point(mb, 1500.0, 5.0, R2_ratio=1.2)
    assert op.torque_Nm == pytest.approx(5.0 + 0.01 * op.w_m, rel=1e-12)
    assert op.speed_error_rpm == pytest.approx(0.2 * op.slip_mech_rpm, rel=1e-12)
    op_a = foc_operating_point(mb, 1500.0, 5.0, R2_ratio=1.2, sensorless=False)
    assert op_a.torque_Nm == pytest.approx(5.0 + 0.01 * 1500.0 * math.pi / 30.0, rel=1e-12)


def test_plot(m):
    fig = plot_speed_error_vs_R2(m, 1500.0, [4.0, 8.0, 12.0], np.linspace(0.8, 1.2, 9))
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    curves = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 9]
    assert len(curves) == 3
    y = curves[-1].get_ydata()
    assert y[0] < 0 < y[-1]


@pytest.mark.parametrize("ratio", [0.8, 1.2])
def test_zero_flux_error_is_an_equilibrium_of_eq10(m, ratio):
    # PAPER.md eq. (10) in the rotor-flux frame with e_d0 = e_q0 = 0 and lam_hat = (M id, 0):
    # the q row, lam_hat_d0 (w_r - w_r_hat) + (M/L2) iq (R2 - R2_hat), must vanish at the
    # sensorless steady state (see imdrive.analysis.foc), i.e. the speed error cancels the
    # R2-error input and no flux error is needed
    op = foc_operating_point(m, 1000.0, 12.0, R2_ratio=ratio)
    n_p = m.pole_pairs
    w_r = n_p * op.w_m
    w_r_hat = n_p * op.speed_est_rpm * math.pi / 30.0
    lam_hat_d0 = m.M_H * op.id_A
    R2_hat = ratio * m.R2_ohm
    q_row = lam_hat_d0 * (w_r - w_r_hat) + m.M_H / m.L2_H * op.iq_A * (m.R2_ohm - R2_hat)
    scale = lam_hat_d0 * abs(w_r - w_r_hat)
    assert scale > 0.1  # a real speed error, so the check is not trivially 0 = 0
    assert abs(q_row) < 1e-9 * scale
    assert op.psi_r_Wb == pytest.approx(lam_hat_d0, rel=1e-12)  # no flux error either
