"""The R2 bias the dead-time compensation's current band causes on the switching bridge at low
speed, and its removal at the source.

Mechanism (kernels/ifoc.py ``commutation_ripple``, ``dead_time_feedforward``): on the bridge a
leg loses ``u/2`` at each of its two commutations, signed by the current *there*; the current
is then off its sample by ``+-delta`` (its ripple), so the loss is 0 while ``|i_x| < delta``
and whole beyond. At 0.1 of the rated speed ``delta`` is about 0.1 A on Table IV, and a
compensation that ramps over a fixed 0.2 A band is short of the loss just past ``delta``: the
residual there holds the current back instead of pushing it through zero, the current stalls
at each zero crossing and its fundamental lags by an angle that falls as ``1/|i|``. The
injection's ``delta i_d`` modulates ``|i|``, hence the lag: a voltage error across the current
in phase with the injection (measured on Table IV at no load: 0.038 V per ampere injected on
the q axis; 0.0004 V on the average model with the same dead time), which the MRAS's voltage
model turns into an in-phase d-axis flux error, read as R2 error. Following the loss's shape
(none near zero, whole from ``delta``) the compensation is whole wherever the loss is.

Measured here on the envelope's cells at 0.1 of the rated speed, at no load and regenerating at
the rated torque, on two machines (Table IV from R1_hat = 0.9 R1: -3.4 and -6.6 % with the
fixed band; the Aalto 2.2 kW machine, 400 V 50 Hz, from R1_hat = R1: -6.0 % at no load), on
the envelope's bridge (2 us dead time compensated as 1.6 us, the online scaling on) from
R2_hat(0) = R2: with the loss's shape within 2 % (+1.6 and -0.1 %; 0.0 and -0.4 % on the
Aalto machine). And the online scale of the compensation,
which nulls the residual's sixth harmonic, learns the true ratio once the compensation has the
loss's shape (Table IV at 0.3 of the rated speed, no load). The bias's sign and size are not a
law: the stall's lag depends on the load angle and R1_hat; at 0.12 of the rated speed from
R1_hat = R1 Table IV ended +0.5 / +1.6 % with the fixed band.
"""

from __future__ import annotations

import pytest

from imdrive import simulate_batch
from imdrive.sweep import load_sweep

pytestmark = pytest.mark.slow  # end to end: 10 closed-loop runs of 38 s on the switching bridge


def _runs(machine: str, R1_ratio: float):
    sw = load_sweep("envelope-full")
    keys, scs = [], []
    for band in ("fixed", "ripple"):
        for load in (0.0, -1.0):
            want = dict(
                speed_pu=0.1, load_pu_available=load, R2_ratio=1.0, R1_ratio=0.9,
                thermal="constant", inverter="bridge",
            )  # fmt: skip
            sc = sw.scenario_for(tuple(want[a.name] for a in sw.axes))
            o = [
                f'machine.preset="{machine}"',
                f'control.dead_time_compensation_band="{band}"',
                # the band this measures: 0.2 A (the default now scales it with the rated
                # current, 0.12 A on the Aalto machine, where the fixed band ends -1.9 %)
                "inverter.sign_band_A=0.2",
                f"estimator.R1_ratio={R1_ratio}",
                # the MRAS's fixed cut-off this was measured with: the cut-off that follows
                # the stator frequency (on in injection-robust since) also lowers what the MRAS
                # reads of the stall's lag (Aalto, no load: -2.6 % instead of -3.4)
                "mras.wc_per_stator_frequency=0",
                # the one-level standstill R1 this was measured with (two levels: R1_hat = R1
                # and the scale started at the residual; the fixed band then ends -2.5 %)
                "mras.R1_standstill_levels=1",
                "simulation.log_every=200",
            ]
            keys.append((band, load))
            scs.append(sc.with_overrides(o))
    b = simulate_batch(scs)
    return {k: row for k, row in zip(keys, b.metrics.itertuples(), strict=True)}


@pytest.mark.parametrize(("machine", "R1_ratio"), [("paper-table-iv", 0.9), ("aalto-2.2kw", 1.0)])
def test_a_band_wider_than_the_commutation_ripple_biases_R2_and_the_bound_removes_it(
    machine, R1_ratio
):
    r = _runs(machine, R1_ratio)
    # the mechanism: with the fixed 0.2 A band R2_hat ends low
    assert min(r[("fixed", 0.0)].R2_error_pct, r[("fixed", -1.0)].R2_error_pct) < -3.0
    # removed at its source: following the loss's shape R2_hat ends within 2 % (the ideal
    # drive's goal; the bridge's is 3 %) and the run is fine
    row = r[("ripple", 0.0)]
    assert abs(row.R2_error_pct) < 2.0
    assert row.verdict == "ok"
    # regenerating, within the bridge's 3 %: since 2026-11-30 the injection runs here at the
    # harmonic farthest from the stator frequency (Table IV: 5 Hz, a side band 1.9 Hz from
    # it, against 1.67 Hz and 1.4 Hz before; none clears the detection filter's 2.4 Hz
    # corner, kernels/gating.py), where the smaller flux response leaves the bridge's residual
    # a larger share: -2.7 % against -0.9 % (Aalto: +0.6 % either way)
    row = r[("ripple", -1.0)]
    assert abs(row.R2_error_pct) < 3.0
    assert not row.lost_control


# the fixed band's scale and R1_hat with each of the scale's signals (control.
# inverter_error_signal): the current PIs' output learned 1.17 and left R1_hat 1.17 R1, the
# stator voltage equation's residual, which sees the over-compensation without the current
# loop between, 1.20 and 1.11 R1; with the loss's shape both within 1.5 % and 4 %
@pytest.mark.parametrize(
    ("signal", "k_fixed_max", "R1_fixed_min"),
    [("stator-voltage", 1.215, 1.08), ("current-loop", 1.2, 1.1)],
)
def test_with_the_bridge_loss_shape_the_online_scale_learns_the_true_ratio(
    signal, k_fixed_max, R1_fixed_min
):
    # Table IV at 0.3 of the rated speed, no load: the ripple at the commutations (about
    # 0.25 A) straddles the fixed band; the sign model's ramp over-compensates inside it,
    # which the sixth-harmonic law takes for a larger compensation and so learns a smaller
    # scale, and the standstill R1_hat keeps the share of the residual the scale did not take
    sw = load_sweep("envelope-full")
    want = dict(
        speed_pu=0.3, load_pu_available=0.0, R2_ratio=1.0, R1_ratio=0.9,
        thermal="constant", inverter="bridge",
    )  # fmt: skip
    sc = sw.scenario_for(tuple(want[a.name] for a in sw.axes))
    scs = [
        sc.with_overrides(
            [
                f'control.dead_time_compensation_band="{band}"',
                "estimator.R1_ratio=1.0",
                f'control.inverter_error_signal="{signal}"',
                # the MRAS drive this was measured on (on the observer's the current-loop
                # signal learns 0.36, not 1.25: the speed estimate's sixth harmonic reaches
                # the current controllers' output; the default stator-voltage signal holds)
                'control.speed_feedback="mras"',
                # one standstill level: its R1_hat keeps the share the scale did not take
                # (two levels identify R1 itself, 1.000 R1 here)
                "mras.R1_standstill_levels=1",
            ]
        )
        for band in ("fixed", "ripple")
    ]
    b = simulate_batch(scs, logs=True, log_every=1000)
    (k_fixed, R1_fixed), (k_ripple, R1_ripple) = (
        (
            1.0 + res.state_final.control[0]["ie_dk"],
            res.state_final.model[0]["R1_hat"] / s.machine.R1_ohm,
        )
        for res, s in zip(b.results, scs, strict=True)
    )
    assert k_fixed < k_fixed_max
    assert R1_fixed > R1_fixed_min
    assert k_ripple == pytest.approx(2.0 / 1.6, rel=0.015)
    assert R1_ripple == pytest.approx(1.0, abs=0.04)
