"""The deprecated keys of the R2-tracking sections ``[compensator]``, ``[injection]``,
``[kalman]`` and ``[flux_injection]`` (issue 38: "a handful of per-unit settings"): each is
accepted with a warning that says the rule or the mechanism that replaced it, with the
measurement behind it (:mod:`imdrive.config.deprecated_keys`), and listed apart in
docs/scenarios.md. Registered when :mod:`imdrive.config.compensator` is imported.
"""

from __future__ import annotations

from imdrive.config.deprecated_keys import deprecated_key, deprecated_twin, deprecated_value
from imdrive.config.injection_backoff import backoff_band
from imdrive.config.r2_kalman import THERMAL_ALPHA_PER_K, THERMAL_RISE_K

#: The adaptive step law's keys (removed in 0.2, :mod:`imdrive.kernels.compensator`): what
#: each patched, and what the model-based law does instead.
_ADAPTIVE_LAW = {
    "fine_gain": "the fine band's level per unit of scaled E; the Kalman law's gain (its "
    "measurement noise [kalman] noise_pu against R2's uncertainty) sets the step",
    "drift_gain": "the share of a fine step integrated into a drift rate; the Kalman law's "
    "second state is R2's drift rate ([kalman] drift_pu)",
    "overshoot_damping": "halving the table's steps after a reversal; the Kalman gain falls as "
    "the measurements agree",
    "drift_min_freq_Hz": "the stator frequency below which the drift rate was reset; the Kalman "
    "law weighs every accepted window by its noise instead",
    "drift_max_ohm": "the drift rate's bound; the Kalman law's drift rate is bounded by its "
    "noise model ([kalman] drift_pu)",
    "drift_unwind_factor": "how fast the drift unwound after a ramp stopped; the Kalman law's "
    "innovation unwinds it",
    "drift_shrink_margin": "the shrink of the error that stopped the drift's integration; the "
    "Kalman law has no integrator to wind up",
    "fine_gain_follows_R2": "the fine step's gain kept as R̂2 moved; the Kalman law divides each "
    "window by its sensitivity at the R̂2 in use",
}
for _key, _why in _ADAPTIVE_LAW.items():
    deprecated_key("compensator", _key, _why + ' (step_law = "adaptive" was removed)')
deprecated_value(
    "compensator",
    "step_law",
    "adaptive",
    "kalman",
    "the model-based law gives the adaptive law's step size, ramp following and damping from "
    "one filter (the envelope sweep: 263 of 267 cells within goal against 259, off the grid "
    "78 of 80 against 80; what it costs: CHANGELOG.md, docs/envelope.md)",
)

#: Keys of mechanisms that a law or a fixed rule replaced in round 4 (issue 38: few settings,
#: each with a measurement of what it buys).
_REPLACED = {
    ("injection", "frequency2_Hz"): "the gating's schedule is the harmonics 1, 2, 3 of "
    "injection.frequency (HARMONICS in config/compensator.py): every preset and study that set "
    "the alternatives set 2 f and 3 f",
    ("injection", "frequency3_Hz"): "as frequency2_Hz: the third frequency is always 3 f",
    ("injection", "headroom_rate_per_s"): "the estimation headroom's loop samples the peak voltage "
    "once per injection period, so its gain is set per period: 0.5 (Table IV's 1 /s at 2 Hz), "
    "HEADROOM_GAIN_PER_PERIOD in run/compensator_blocks.py",
    ("injection", "headroom_gain_per_period"): "as headroom_rate_per_s: the gain is 0.5 per "
    "injection period on every machine",
    ("injection", "compensate_filter"): "undoing the MRAS's comparison filter at the side bands "
    "did not improve R2_hat: on injection-robust at 0.05, 0.1 and 0.2 x rated speed, rated "
    "motoring and regenerating load, R2_hat(0) = 0.8, 1.2 R2 on Table IV, Aalto 2.2 kW and "
    "Krause 50 hp, 31 of 36 runs ended within 0.1 % of R2 of each other, 4 ended farther with "
    "it and 1 closer, and 34 of 36 within 2 % either way",
    ("injection", "lowpass_rad_s"): "it filtered the detected product for display only; the "
    "product is logged every sample (e_d0_demod): filter it where it is plotted",
    ("injection", "t_on_s"): "the injection starts with the compensator, at compensator.t_on_s "
    "(which moves with the drive's sequence as the profiles do): every preset, sweep and study "
    "that set both set them equal",
    ("compensator", "gain_DE_pu"): "the change of E per period (DE) is scaled as E, by gain_E_pu: "
    "the paper's Tables I and II quantise both on the same micro-weber thresholds, and every "
    "preset, sweep and study set the two equal (1e6 and 1000 /Wb)",
    ("compensator", "gain_DE_per_Wb"): "as gain_DE_pu: DE is scaled as E (gain_E_pu)",
    ("compensator", "average"): "the input is always its mean over the decision window (a "
    "boxcar anti-aliasing filter; for the demodulated input it is the synchronous detection "
    "itself), as every preset and study had it: a sample at the window's end left R2_hat at its "
    "start on injection-fig5/6-realistic (+-20 %, 0.39 % with the mean), and with the paper's "
    "e_d0 input neither converges (paper-fig5/6, 1000 and 150 rpm, average and realistic drive: "
    "-50 ... +50 % either way)",
    ("injection", "headroom"): "the injection's amplitude backs off near the voltage limit "
    "exactly when the field weakening is on (its default; no preset or study set it): with the "
    "field weakening on and it off, R2_hat ended 0.42 % and the speed 0.23 rpm off at 0.93 x "
    "rated speed and load on Table IV (0.00 with it; Aalto 2.2 kW 0.48 rpm), without the field "
    "weakening it changed nothing (R2_hat held at +20 % near base speed either way)",
    ("compensator", "gate_hold_periods"): "one whole decision window after a gated one is held on "
    "every drive (GATE_HOLD_PERIODS in run/compensator_blocks.py), the value every preset and "
    "study used",
    ("compensator", "input"): "the input is e_d0 detected synchronously with the injection "
    "exactly when the injection runs (injection.amplitude_pu > 0), and e_d0 itself, the paper's, "
    "when it does not: demodulated without the injection R2_hat never moves, and e_d0 under the "
    "injection is its ripple; every preset, sweep and study paired them so",
    ("injection", "headroom_from"): "the injection's back-off band follows the voltage the "
    "field weakening holds: with the estimation headroom from 0.04 to 0.10 above "
    "injection.headroom_voltage (0.92-0.98 at 0.88), without it 0.05 either side of "
    "control.field_weakening_voltage (0.85-0.95 at 0.9), as every preset, sweep, study and test "
    "paired them (config/injection_backoff.py). With the estimation headroom, moving the "
    "band 0.02 either way moved R2_hat's end by at most 0.012 % (injection-robust, Table IV and "
    "Aalto 2.2 kW, 0.6-1.2 x rated speed, load steps); without it the band decided whether R2 "
    "was tracked near base speed at all (0.85 x rated speed, rated load: held at +20 % with "
    "0.85-0.95, tracked with 0.87-0.97), a gap the estimation headroom closes at any band",
    ("compensator", "period_s"): "the decision window is one injection period with the "
    "injection (the shortest that holds whole periods of it and its harmonics) and 10 ms without "
    "(the paper's e_d0 input). A longer window bought nothing: two injection periods ended at "
    "the same R2_hat in twice the time (the Kalman law on injection-fig5 and injection-robust: "
    "within 0.004 %, 3.0 s to 2 % against 1.5 s, also with noise_pu over sqrt 2; the table law "
    "on injection-fig5-realistic: 0.392 % either way, 8 s against 4 s), and with the table law "
    "the window and G_CR_pu say one thing, its rate (two periods with twice G_CR_pu: 4 s and "
    "0.392 %, as one); the paper's e_d0 law ran to its clamp at 5, 10 and 20 ms alike "
    "(paper-fig5: -50 %)",
    ("injection", "decouple_slip_fmin_pu"): "the slip decoupling fades in from 0.3 of the rated "
    "stator frequency to 0.6 on every drive (SLIP_DECOUPLING_FROM_PU in "
    "run/compensator_blocks.py), the value every preset, sweep and study used: 0.15 or 0.45 "
    "moved R2_hat's end by at most 0.04 % on the ideal drive (3 machines, 0.1-2 x rated speed) "
    "and by one table step either way at 0.3-0.5 x rated speed on the realistic bridge, better "
    "at one point and worse at another",
    ("kalman", "prior_pu"): "the model-based law's prior is the rotor's resistance swing between "
    "ambient and its rated temperature rise, compensator.thermal_alpha_per_K x thermal_rise_K "
    "(0.31 at their defaults; config/r2_kalman.py prior_pu): from R2_hat(0) = 0.7 and 1.2 R2 on "
    "Table IV, the Aalto 2.2 kW machine and Krause 50 hp R2_hat entered 2 % at the same "
    "instant as with 0.3 and ended within 0.04 % of it",
    ("injection", "headroom_to"): "as headroom_from: the band's top is 0.10 above "
    "injection.headroom_voltage, or 0.05 above control.field_weakening_voltage without it",
}


def _compensator_start(data: dict):
    comp = data.get("compensator")
    return comp.get("t_on_s", 0.0) if isinstance(comp, dict) else 0.0


def _thermal_prior(data: dict, v) -> bool:
    """Whether ``v`` is the prior the thermal constants give (``kalman.prior_pu``'s rule):
    0.3, its old default, is not, and says so."""
    comp = data.get("compensator")
    comp = comp if isinstance(comp, dict) else {}
    alpha = comp.get("thermal_alpha_per_K", THERMAL_ALPHA_PER_K)
    rise = comp.get("thermal_rise_K", THERMAL_RISE_K)
    return all(isinstance(x, (int, float)) for x in (v, alpha, rise)) and v == alpha * rise


def _injecting(data: dict) -> bool:
    inj = data.get("injection")
    inj = inj if isinstance(inj, dict) else {}
    amp = inj.get("amplitude_pu")
    amp = inj.get("amplitude_A") if amp is None else amp
    return isinstance(amp, (int, float)) and amp > 0


def _backoff_edge(data: dict, edge: int, v) -> bool:
    """Whether ``v`` is the back-off band's edge ``edge`` (0: from, 1: to) the rule gives."""
    inj, ctl = (
        data.get(k) if isinstance(data.get(k), dict) else {} for k in ("injection", "control")
    )
    hv, fw_v = inj.get("headroom_voltage"), ctl.get("field_weakening_voltage", 0.9)
    if not all(isinstance(x, (int, float)) for x in (v, fw_v, 0.0 if hv is None else hv)):
        return False
    return abs(v - backoff_band(hv, fw_v)[edge]) < 1e-12


#: The values of a replaced key that ask for what its rule does (a scenario written out in
#: full by an earlier release states every key): dropped without a warning.
_ASKS_FOR_THE_RULE = {
    ("injection", "t_on_s"): lambda data, v: v == _compensator_start(data),
    ("compensator", "average"): lambda data, v: v is True,
    ("compensator", "input"): lambda data, v: v == ("demodulated" if _injecting(data) else "e_d0"),
    ("compensator", "period_s"): lambda data, v: v == 0.01 and not _injecting(data),
    ("injection", "decouple_slip_fmin_pu"): lambda data, v: v == 0.3,
    ("kalman", "prior_pu"): _thermal_prior,
    ("injection", "headroom_from"): lambda data, v: _backoff_edge(data, 0, v),
    ("injection", "headroom_to"): lambda data, v: _backoff_edge(data, 1, v),
}
for (_section, _key), _why in _REPLACED.items():
    deprecated_key(_section, _key, _why, _ASKS_FOR_THE_RULE.get((_section, _key)))
for _n in ("frequency2", "frequency3"):
    deprecated_key("injection", f"{_n}_pu", f"as {_n}_Hz: the schedule is the harmonics of f")
# The gate's thresholds in absolute units: no preset states them so (their defaults and the
# recommended preset's values are per-unit of the machine).
for _key in ("gate_speed", "gate_iq", "gate_band"):
    _unit = {"gate_speed": "rpm", "gate_iq": "A", "gate_band": "Hz"}[_key]
    deprecated_twin("compensator", f"{_key}_{_unit}", f"{_key}_pu")
# The table law's scalings and step, the clamps, the injections' amplitude and frequency in
# absolute units (round 7, issue 38): each is one setting with its per-unit twin
# (config/pairs.py), and the presets state the twin with the value that gives the same float
# on Table IV (or leave it to its default, which is the paper's number there).
for _section, _key, _twin in (
    ("compensator", "gain_E_per_Wb", "gain_E_pu"),
    ("compensator", "G_CR_ohm", "G_CR_pu"),
    ("compensator", "R2_min_ohm", "R2_min_ratio"),
    ("compensator", "R2_max_ohm", "R2_max_ratio"),
    ("injection", "frequency_Hz", "frequency_pu"),
    ("flux_injection", "frequency_Hz", "frequency_pu"),  # (config/estimators.py's section)
):
    deprecated_twin(_section, _key, _twin)
# 0 A was its default (the injection off): a scenario written out in full states it
deprecated_twin("injection", "amplitude_A", "amplitude_pu", unset=0.0)
