"""The sliding-mode MRAS speed estimator (``control.speed_feedback = "smo-mras"``,
:mod:`imdrive.kernels.estimators.smo_mras`).

Kernel alone, on a hand-made plant (the current model at a known speed, the voltage that makes
the voltage model reproduce its flux exactly, ``wc = 0``):

* with the true flux in both models the sliding variable stays at zero and the equivalent
  control is the true speed; with the pure relay (``phi = 0``) the sliding variable chatters
  within ``W Ts`` and the estimate within ``(1 - exp(-w_f Ts)) W``;
* a speed step smaller than ``W`` is followed as the designed first-order lag
  ``1 - exp(-w_f t)``; a larger one is first slewed at ``w_f W``.

Closed loop through the public API on the average drive (preset ``sensorless``, Table IV
machine), measured: the estimate within 0.06 rpm of the speed at 1000 rpm and within 0.005 rpm
at 150, 30 and 10 rpm, motoring and regenerating at speed; on a 1000 rpm/s ramp it lags by the
designed ``a / w_f`` (7.96 rpm at 20 Hz). Low-speed regeneration is outside its region, as
for Schauder's MRAS (the same two models): it loses the speed at 60 rpm with -12 N m, 20 rpm
with -6 N m, 10 rpm with -3 N m, and holds 80, 40 and 20 rpm with those loads.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from imdrive.config.scenario import Scenario
from imdrive.kernels.estimators.common import current_model_step
from imdrive.kernels.estimators.registry import ESTIMATOR_INPUT
from imdrive.kernels.estimators.smo_mras import KERNEL, smo_mras_estimate
from imdrive.kernels.model import MODEL_STATE
from imdrive.kernels.records import new_record
from imdrive.run.simulate import simulate

# Table IV machine (ohm, H), control period (s), and the default design: W = 0.1 x 2 pi 60,
# w_f = 2 pi 20 rad/s
R1, R2, LL1, LL2, M = 0.435, 0.816, 0.002, 0.002, 0.0693
L2 = LL2 + M
SIGMA_L1 = LL1 + M - M * M / L2
TS = 1e-4
W = 0.1 * 2 * math.pi * 60
W_F = 2 * math.pi * 20


def _kernel_run(w_of_t, n, phi=None, w_sl=3.0, i_amp=10.0):
    """Run the kernel ``n`` periods on a plant at electrical speed ``w_of_t(t)`` (rad/s).

    The stator current is a constant-amplitude vector at ``w + w_sl``; the plant's rotor flux
    follows the exact current model at the true speed; the voltage is the one that makes the
    voltage model's increment equal to the plant's flux increment. Both models start at the
    true flux, the estimate at the true speed. Returns rows ``(t, w, w_hat, sigma, u)``.
    """
    phi = 2 * W * TS if phi is None else phi
    p = new_record(KERNEL.params, wc=0.0, W=W, phi=phi, w_f=W_F, psi2_min=0.01)[0]
    m = new_record(MODEL_STATE, R1_hat=R1, R2_hat=R2, Ll1_hat=LL1, Ll2_hat=LL2, M_hat=M)[0]
    w = w_of_t(0.0)
    lam = M * i_amp / complex(1.0, w_sl * L2 / R2)  # steady state of the current model
    s = new_record(KERNEL.state, lam_v_ab=lam, lam_i_ab=lam, lam_f_ab=lam, u=w, w_r_hat=w)[0]
    inp = np.zeros(1, dtype=ESTIMATOR_INPUT)[0]
    inp["Ts"] = TS
    theta = 0.0
    i_prev = complex(i_amp, 0.0)
    rows = []
    for k in range(1, n + 1):
        w = w_of_t((k - 1) * TS)
        theta += (w + w_sl) * TS
        i = i_amp * complex(math.cos(theta), math.sin(theta))
        lam_new = current_model_step(lam, w, R2, L2, M, i_prev, i, TS)
        v = R1 * 0.5 * (i + i_prev) + (SIGMA_L1 * (i - i_prev) + (M / L2) * (lam_new - lam)) / TS
        inp["v_ab"], inp["i_prev_ab"], inp["i_ab"], inp["theta_e"] = v, i_prev, i, theta
        w_hat, _ = smo_mras_estimate(p, m, s, inp)
        rows.append((k * TS, w_of_t(k * TS), w_hat, s["sigma"], s["u"]))
        lam, i_prev = lam_new, i
    return np.array(rows)


def test_true_flux_in_both_models_keeps_sigma_at_zero_and_the_speed_exact():
    out = _kernel_run(lambda t: 300.0, 2000)
    assert np.abs(out[:, 3]).max() < 1e-12  # rad
    np.testing.assert_allclose(out[:, 2], 300.0, rtol=1e-12)
    np.testing.assert_allclose(out[:, 4], 300.0, rtol=1e-12)


def test_pure_relay_chatters_within_W_Ts_and_its_filtered_ripple():
    out = _kernel_run(lambda t: 300.0, 2000, phi=0.0)
    a = 1.0 - math.exp(-W_F * TS)
    assert np.abs(out[:, 3]).max() <= 1.01 * W * TS  # the relay's step in the flux angle
    assert out[:, 4].std() > 0.9 * W  # u switches between w_hat +- W ...
    assert np.abs(out[:, 2] - 300.0).max() <= 1.01 * a * W  # ... the estimate by a W at most
    assert abs(out[1000:, 2].mean() - 300.0) < 0.05 * a * W


def test_speed_step_below_W_is_followed_as_the_designed_first_order_lag():
    t0, dw = 0.01, 0.5 * W
    out = _kernel_run(lambda t: 300.0 + (dw if t >= t0 else 0.0), 600)
    t, w_hat, sigma = out[:, 0], out[:, 2], out[:, 3]
    ideal = 300.0 + dw * (1.0 - np.exp(-W_F * np.clip(t - t0, 0.0, None)))
    after = t > t0 + 1e-3  # the inner (boundary-layer) loop settles in a few periods
    assert np.abs(w_hat - ideal)[after].max() < 0.03 * dw  # measured 2.1 %
    assert np.abs(sigma).max() < 2 * W * TS  # inside the boundary layer: still sliding


def test_speed_step_above_W_is_slewed_at_w_f_W():
    t0, dw = 0.01, 100.0
    out = _kernel_run(lambda t: 300.0 + (dw if t >= t0 else 0.0), 600)
    t, w_hat = out[:, 0], out[:, 2]
    k0, k1 = np.searchsorted(t, t0 + 5e-4), np.searchsorted(t, t0 + 5e-3)
    slope = (w_hat[k1] - w_hat[k0]) / (t[k1] - t[k0])
    a = 1.0 - math.exp(-W_F * TS)
    assert slope == pytest.approx(a / TS * W, rel=1e-3)  # w_f W, discretised
    assert slope == pytest.approx(W_F * W, rel=0.01)
    # the error falls below W after (dw - W) / (w_f W), then the first-order lag takes over
    t_in = t[np.argmax(300.0 + dw - w_hat < W)] - t0
    assert t_in == pytest.approx((dw - W) / (W_F * W), rel=0.03)


# -- closed loop ----------------------------------------------------------------------------


def _scenario(rpm, load, *extra):
    return Scenario.read(
        "sensorless",
        [
            'control.speed_feedback="smo-mras"',
            f"control.speed_ref_rpm={{initial=0, changes=[{{at=0.5, to={rpm}, over=1.0}}]}}",
            f"load.torque_Nm={{initial=0, changes=[{{at=2.0, to={load}}}]}}",
            "simulation.t_end_s=5.0",
            *extra,
        ],
    )


KRAUSE = 'machine.preset="krause-3hp"'
#: (rpm, N m, extra overrides) -> bound on |mean estimate error| over the last second, rpm
HOLDS = {
    (1000, 12, ()): 0.1,  # measured +0.003 (+0.059 with the current model on the chord)
    (1000, -12, ()): 0.1,  # regenerating at speed: +0.003
    (1500, 6, ()): 0.1,  # +0.002
    (150, 12, ()): 0.01,  # +0.0008
    (150, -12, ()): 0.01,  # +0.0001
    (30, 12, ()): 0.01,  # +0.0004
    (10, 6, ()): 0.01,  # -0.003
    (80, -12, ()): 0.01,  # regeneration, just above the boundary below
    (40, -6, ()): 0.01,
    (20, -3, ()): 0.01,
    (1000, 12, (KRAUSE,)): 0.1,  # the second machine (same circuit, J = 0.089 kg m^2)
    (150, -12, (KRAUSE,)): 0.01,
}
#: low-speed regeneration points where the speed is lost (a limit cycle of hundreds of rpm)
LOST = ((60, -12), (20, -6), (10, -3))


@pytest.fixture(scope="module")
def runs():
    # one drive at a time: the drive kernel of the estimator is compiled once for all the tests
    # (imdrive warm-up), a batch kernel would be compiled for its records on top
    cases = [*HOLDS, *((rpm, load, ()) for rpm, load in LOST)]
    return {
        (r, l, e): SimpleNamespace(**simulate(_scenario(r, l, *e)).metrics(window_s=1.0))
        for r, l, e in cases
    }


@pytest.mark.parametrize("case", list(HOLDS), ids=lambda c: f"{c[0]}rpm{c[1]:+d}Nm{len(c[2])}")
def test_closed_loop_holds_the_speed_and_the_estimate(runs, case):
    row = runs[case]
    assert not row.diverged
    assert abs(row.final_speed_rpm - case[0]) < 0.5
    assert row.speed_ripple_rpm < 0.2  # measured 0.08 at 10 rpm, < 0.003 elsewhere
    assert abs(row.speed_est_error_rpm) < HOLDS[case]


@pytest.mark.parametrize("rpm, load", LOST)
def test_low_speed_regeneration_is_outside_its_region(runs, rpm, load):
    """Measured, not wanted: at a low stator frequency in regeneration the speed estimate runs
    away (the region of Schauder's MRAS too, which shares both models). The speed swings by
    more than 100 rpm about a reference of at most 60 rpm, and the estimate's mean error is
    -30 rpm at 60 rpm, -380 rpm at 20 rpm, -10 rpm at 10 rpm (-3 N m; the swing is about its
    reference since the default current limit is 1.5 times the rated peak current). With the
    current model on the chord between the current samples the 60 rpm point's was +202 rpm."""
    row = runs[(rpm, load, ())]
    assert row.speed_ripple_rpm > 100.0  # measured 558, 356, 207 rpm over the last second
    assert abs(row.speed_est_error_rpm) > 5.0  # measured -30, -380, -10 rpm


def test_ramp_lag_is_the_designed_equivalent_control_lag():
    """On the preset's 1000 rpm/s ramp the estimate lags the speed by a / w_f (first order)."""
    res = simulate(_scenario(1000, 12, "simulation.t_end_s=1.5"))
    t = np.asarray(res.signals["time_s"])
    err = np.asarray(res.signals["speed_est_rpm"]) - np.asarray(res.signals["speed_rpm"])
    mid = (t > 0.9) & (t < 1.4)  # ramp from 0.5 to 1.5 s, after 5 time constants
    assert err[mid].mean() == pytest.approx(-1000.0 / W_F, rel=0.02)  # measured -7.97 rpm
    assert np.abs(res.signals["smo_sigma_rad"][mid]).max() < 2 * W * TS
