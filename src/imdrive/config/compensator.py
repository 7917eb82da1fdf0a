"""Settings of the fuzzy rotor-resistance compensator and of its persistent excitation
(sections ``[compensator]``, ``[injection]``).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import model_validator

from imdrive.config.deprecated_keys import deprecated_key, deprecated_twin, deprecated_value
from imdrive.config.r2_kalman import KalmanLawSettings  # noqa: F401  (the law registers)
from imdrive.config.r2_laws import law_names
from imdrive.config.validation import Bool, Float, setting, settings
from imdrive.errors import ConfigError

#: The gating's frequency schedule: these multiples of the injection frequency f. Near the
#: stator frequency the lowest of them at least ``compensator.gate_band_pu`` f from it is
#: injected (kernels/gating.py). Whole multiples, a decision window of whole periods of f holds
#: whole periods of each. Every preset and study used 1, 2, 3 f when they could be set apart
#: (``injection.frequency2_*``, ``frequency3_*``: deprecated).
HARMONICS = (1, 2, 3)


@settings("compensator")
class CompensatorSettings:
    """The fuzzy rotor-resistance compensator (``[compensator]``, paper §4).

    ``gain_E_pu`` scales e_d0 and its change per period (E and DE) before the quantiser
    (thresholds 0.25 ... 5), in per-unit of ``1/ψ_rated``: the paper's 1e6 /Wb (its
    micro-weber thresholds) is 463116 on Table IV. One gain for both: the paper's Tables I and
    II quantise E and DE on the same micro-weber thresholds, and every preset, sweep and study
    set the two equal (``gain_DE_pu`` and ``gain_DE_per_Wb`` are deprecated). ``G_CR_pu`` is
    the change of R2_hat per output level and period in per-unit of the initial R̂2. Unset,
    these and the gate's thresholds are the paper's numbers on Table IV scaled to the machine
    (:mod:`imdrive.config.compensator_gains`). The clamps ``R2_min_ratio``, ``R2_max_ratio``
    default to 0.5 and 2 times the initial estimate. ``period_s`` defaults to 10 ms, or to one
    injection period with ``input = "demodulated"``.

    Each of these had an absolute spelling (``gain_E_per_Wb``, ``G_CR_ohm``, ``R2_min_ohm``,
    ``R2_max_ohm``; deprecated twins since round 7, they still act with a warning): the
    per-unit value times its base is the absolute one, and every preset's absolute value is
    reproduced to the last bit by the per-unit value it states now, or by the default that is
    the paper's number on Table IV (tests/config/test_deprecated_twins.py).
    """

    enabled: Annotated[Bool, setting("run the fuzzy R2 compensator")] = False
    t_on_s: Annotated[
        Float,
        setting(
            "time R2 tracking starts, the compensator and its injection ([injection]), in the "
            "duty cycle's time: it moves with the speed and load profiles when the drive's "
            "sequence delays them (the premagnetisation, the standstill R1 test's wait; "
            "config/sequence.py)",
            "s",
            ge=0.0,
        ),
    ] = 0.0
    period_s: Annotated[
        Float | None,
        setting(
            "decision period",
            "s",
            gt=0.0,
            default_doc='0.01; one injection period with input = "demodulated"',
        ),
    ] = None
    gain_E_per_Wb: Annotated[
        Float | None,
        setting(
            "scaling of e_d0 before the 13-level quantiser (1e6: the paper's µWb thresholds)",
            "1/Wb",
            gt=0.0,
            default_doc="the paper's 1e6 on Table IV scaled by 1/ψ_rated "
            "(config/compensator_gains.py)",
        ),
    ] = None
    G_CR_ohm: Annotated[
        Float | None,
        setting(
            "change of R̂2 per output level and period",
            "ohm",
            ge=0.0,
            default_doc="the paper's 0.001 on Table IV scaled by the machine's R2",
        ),
    ] = None
    G_CR_pu: Annotated[
        Float | None,
        setting(
            "change of R̂2 per output level and period in per-unit of the initial R̂2, so the "
            "step follows the machine",
            ge=0.0,
            default_doc="the paper's 0.001 ohm on Table IV scaled by the machine's R2 (0.12 % "
            "of it)",
        ),
    ] = None
    gain_E_pu: Annotated[
        Float | None,
        setting(
            "scaling of e_d0 and of its change per period (E and DE) before the 13-level "
            "quantiser, in per-unit of 1/ψ_rated (the scaling is gain_E_pu / ψ_rated, 1/Wb)",
            gt=0.0,
            default_doc="the paper's 1e6 /Wb on Table IV: 1e6 × its ψ_rated, 463116",
        ),
    ] = None
    R2_min_ratio: Annotated[
        Float | None,
        setting(
            "lower clamp of R̂2 as a multiple of the initial R̂2",
            gt=0.0,
            default_doc="0.5",
        ),
    ] = None
    R2_max_ratio: Annotated[
        Float | None,
        setting(
            "upper clamp of R̂2 as a multiple of the initial R̂2",
            gt=0.0,
            default_doc="2",
        ),
    ] = None
    R2_min_ohm: Annotated[
        Float | None,
        setting("lower clamp of R̂2", "ohm", gt=0.0, default_doc="0.5 × the initial R̂2"),
    ] = None
    R2_max_ohm: Annotated[
        Float | None,
        setting("upper clamp of R̂2", "ohm", gt=0.0, default_doc="2 × the initial R̂2"),
    ] = None
    table: Annotated[
        Literal["paper", "rules"],
        setting('"paper": the printed Table III; "rules": compiled from the fitted rule base'),
    ] = "paper"
    input: Annotated[
        Literal["e_d0", "demodulated"],
        setting(
            '"e_d0": the paper\'s input; "demodulated": e_d0 detected synchronously with the '
            "injection ([injection])"
        ),
    ] = "e_d0"
    gating: Annotated[
        Bool | None,
        setting(
            "freeze R̂2 during speed and load transients and in voltage saturation, and move "
            "the injection frequency away from the stator frequency (kernels/compensator.py)",
            default_doc='on with input = "demodulated", off with "e_d0"',
        ),
    ] = None
    gate_speed_rpm: Annotated[
        Float | None,
        setting(
            "gating: speed-reference change within a period, or mean speed error over it, "
            "above which the period is a transient (in field weakening the error weighted by "
            "the speed loop's gain, k^2 with the flux-scaled speed gains)",
            "rpm",
            gt=0.0,
            default_doc="1 rpm on Table IV scaled by the rated slip speed (0.0126 × it)",
        ),
    ] = None
    gate_iq_A: Annotated[
        Float | None,
        setting(
            "gating: change of the period-mean iq* from one period to the next above which the "
            "period is a load transient",
            "A",
            gt=0.0,
            default_doc="0.3 A on Table IV scaled by machine.rated_current_A",
        ),
    ] = None
    gate_speed_pu: Annotated[
        Float | None,
        setting(
            "gating: speed-reference change within a period, or mean speed error over it, "
            "above which the period is a transient, per-unit of the machine's rated slip speed "
            "(in field weakening the error weighted by the speed loop's gain, k^2 with the "
            "flux-scaled speed gains)",
            gt=0.0,
            default_doc="0.0126: 1 rpm of Table IV's 79 rpm rated slip",
        ),
    ] = None
    gate_iq_pu: Annotated[
        Float | None,
        setting(
            "gating: change of the period-mean iq* from one period to the next above which the "
            "period is a load transient, per-unit of the machine's rated current "
            "(machine.rated_current_A, peak)",
            gt=0.0,
            default_doc="0.036: 0.3 A of Table IV's 8.3 A",
        ),
    ] = None
    gate_voltage: Annotated[
        Float,
        setting(
            "gating: voltage use (fraction of Vdc/√3) from which the period counts as saturated",
            gt=0.0,
        ),
    ] = 0.97
    gate_band_pu: Annotated[
        Float | None,
        setting(
            "gating: the injection frequency is switched to another harmonic of it when "
            "|stator frequency| is within this of it, per-unit of the first injection frequency "
            "(0: never)",
            ge=0.0,
            default_doc="0.75 (1.5 Hz of Table IV's 2 Hz)",
        ),
    ] = None
    gate_band_Hz: Annotated[
        Float | None,
        setting(
            "gating: the injection frequency is switched when |stator frequency| is within this "
            "of it (0: never)",
            "Hz",
            ge=0.0,
            default_doc="0.75 of the first injection frequency (1.5 Hz of Table IV's 2 Hz)",
        ),
    ] = None
    step_law: Annotated[
        Literal[law_names()],  # the paper's table and every registered law (config/r2_laws.py)
        setting(
            '"table": R̂2 changes by G_CR_ohm × the table\'s level (the paper); "kalman": the '
            "detected error over its analytic sensitivity, filtered by a Kalman filter on R2 "
            "and its drift rate (section [kalman], kernels/r2_kalman.py); the table's gains "
            'then have no effect. "adaptive" (deprecated) runs as "kalman"'
        ),
    ] = "table"

    thermal_model: Annotated[
        Bool,
        setting(
            "rotor thermal model (rotor copper losses -> first-order thermal network -> "
            "temperature -> R̂2) that carries R̂2 while the compensator holds it and is "
            "recalibrated by its estimate whenever R2 is observable (kernels/compensator_range.py, "
            "thermal_step)"
        ),
    ] = False
    thermal_time_constant_s: Annotated[
        Float, setting("thermal model: the rotor's thermal time constant", "s", gt=0.0)
    ] = 1200.0
    thermal_rise_K: Annotated[
        Float,
        setting(
            "thermal model: the rotor's temperature rise above ambient at the machine's rated "
            "rotor copper losses (its thermal resistance in per-unit of the machine: "
            "config/perunit.py; 80 K: the class B limit of IEC 60034-1)",
            "K",
            gt=0.0,
        ),
    ] = 80.0
    thermal_alpha_per_K: Annotated[
        Float,
        setting(
            "thermal model: temperature coefficient of R2 (copper 0.00393, aluminium 0.00403)",
            "1/K",
            gt=0.0,
        ),
    ] = 0.00393

    @model_validator(mode="after")
    def _clamps_in_order(self):
        lo, hi = self.R2_min_ohm, self.R2_max_ohm
        if lo is not None and hi is not None and not lo < hi:
            raise ConfigError("R2_min_ohm", "must be < compensator.R2_max_ohm")
        return self


@settings("injection")
class InjectionSettings:
    """Persistent excitation (``[injection]``): a sinusoid added to the flux-current reference.

    R2 identification from a low-frequency AC flux component is Kubota & Matsuse (IEEE Trans.
    Ind. Appl. 30(5), 1994); feeding its demodulated flux error to the paper's table is ours.

    ``amplitude_pu`` unset or 0 switches it off. The compensator's ``input = "demodulated"``
    feeds on e_d0 detected synchronously with this sinusoid; its period must be a whole number of
    periods of every injection frequency it uses (the default compensator period for that
    input is one; :func:`check_whole_injection_periods`).
    """

    amplitude_A: Annotated[
        Float | None,
        setting(
            "amplitude of the sinusoid added to id* (0: off)",
            "A",
            ge=0.0,
            default_doc="unset: amplitude_pu (0: off)",
        ),
    ] = None
    amplitude_pu: Annotated[
        Float | None,
        setting(
            "the amplitude of the sinusoid added to id* in per-unit of the machine's rated "
            "magnetising current ψ_rated/M (peak; 0: off), so the excitation follows the machine",
            ge=0.0,
            lt=1.0,
            default_doc="0 (off)",
        ),
    ] = None
    frequency_Hz: Annotated[
        Float | None,
        setting(
            "frequency of the sinusoid",
            "Hz",
            gt=0.0,
            default_doc="Table IV's 2 Hz scaled by the machine's rotor corner R2/(2π L2), to "
            "whole control periods (config/compensator_gains.py injection_frequency_Hz)",
        ),
    ] = None
    frequency_pu: Annotated[
        Float | None,
        setting(
            "the frequency in per-unit of the rotor's corner frequency R̂2/(2π L̂2) of the "
            "controller's starting model, where the in-phase sensitivity of the detection "
            "peaks; rounded so a period is a whole number of control periods",
            gt=0.0,
            default_doc="Table IV's 2 Hz scaled by the machine's rotor corner R2/(2π L2) "
            "(1.098 × it), to whole control periods (config/compensator_gains.py "
            "injection_frequency_Hz): exactly 2 Hz on Table IV",
        ),
    ] = None
    headroom_from: Annotated[
        Float,
        setting(
            "with the field weakening on (control.field_weakening), the amplitude backs off "
            "as the voltage use (peak over each injection period) rises from headroom_from to "
            "headroom_to, and is off in field weakening unless headroom_voltage is set; the "
            "compensator freezes below half amplitude (kernels/compensator_range.py, "
            "injection_headroom): the voltage use where it starts to fall",
            gt=0.0,
        ),
    ] = 0.85
    headroom_to: Annotated[
        Float, setting("headroom: voltage use where it reaches zero", gt=0.0)
    ] = 0.95
    headroom_voltage: Annotated[
        Float | None,
        setting(
            "estimation headroom: the peak voltage use per injection period (fraction of "
            "Vdc/√3, at most headroom_from) the field weakening holds while the injection "
            "runs, so near and above base speed the flux is lowered a few percent and the "
            "injection keeps its full amplitude, also in field weakening "
            "(kernels/compensator_range.py, headroom_weakening_input); needs "
            "control.field_weakening",
            gt=0.0,
            lt=1.0,
            default_doc="unset: no lowering, and no injection in field weakening",
        ),
    ] = None
    decouple_slip: Annotated[
        Bool,
        setting(
            "detection: subtract from e_d0 the part the slip couples in from the MRAS's "
            "q-axis flux error, w_s T2_hat/(1 + s T2_hat) e_q0 (kernels/detection.py, "
            "slip_coupling); matters at large slip (full load above base speed)"
        ),
    ] = True
    decouple_slip_fmin_pu: Annotated[
        Float,
        setting(
            "decouple_slip: the stator frequency, per-unit of the rated one, from which the "
            "correction fades in (full at twice it); below it e_q0 is mostly the voltage "
            "model's error (R1, inverter), not the rotor's q flux",
            ge=0.0,
            lt=1.0,
        ),
    ] = 0.3


def injection_amplitude_given(inj) -> float:
    """The injection's amplitude as stated, in its own unit (per-unit or, deprecated, A): 0
    when neither ``amplitude_pu`` nor ``amplitude_A`` is set; whether it is on is its sign."""
    if inj.amplitude_pu is not None:
        return inj.amplitude_pu
    return inj.amplitude_A if inj.amplitude_A is not None else 0.0


def _first_frequency(inj) -> float:
    """The injection frequency without the scenario's machine (no resolved values at hand):
    as given, else Table IV's default."""
    from imdrive.config.compensator_gains import INJECTION_TABLE_IV_HZ

    return inj.frequency_Hz if inj.frequency_Hz is not None else INJECTION_TABLE_IV_HZ


def decision_period_steps(
    comp: CompensatorSettings, inj: InjectionSettings, Ts: float, r=None
) -> int:
    """The compensator's decision period in control periods (at least one).

    ``compensator.period_s`` if given, else one injection period with ``input =
    "demodulated"``, else 10 ms; rounded to whole control periods of ``Ts`` s. ``r``: the
    scenario's per-unit values resolved (:func:`imdrive.config.perunit.resolve`), whose
    injection frequency is used when given.
    """
    if comp.period_s is not None:
        period = comp.period_s
    elif comp.input == "demodulated":
        period = 1.0 / (_first_frequency(inj) if r is None else r.inj_f1)
    else:
        period = 0.01
    return max(int(round(period / Ts)), 1)


def injection_frequencies_in_use(
    comp: CompensatorSettings, inj: InjectionSettings, r=None
) -> list[tuple[str, float]]:
    """``(key, Hz)`` of each injection frequency the compensator's decision period must hold
    whole periods of, so that the synchronous detection averages over whole periods.

    The injection frequency with the demodulated input; with the gating's frequency schedule
    (a band ``compensator.gate_band_pu`` > 0) its harmonics 2 f and 3 f (:data:`HARMONICS`),
    named by the key that sets them. None without injection or without the compensator.
    ``r``: the resolved per-unit values (their frequency and amplitude replace the absolute
    keys, named ``..._pu`` then).
    """
    amp = injection_amplitude_given(inj) if r is None else r.inj_amp
    if not (comp.enabled and amp > 0.0):
        return []
    key = (
        "injection.frequency_pu"
        if r is not None and inj.frequency_pu is not None
        else ("injection.frequency_Hz")
    )
    f1 = _first_frequency(inj) if r is None else r.inj_f1
    if r is not None:
        band = r.gate_band
    elif comp.gate_band_Hz is not None:
        band = comp.gate_band_Hz
    else:  # as config/compensator_gains.py resolves it
        from imdrive.config.compensator_gains import GATE_BAND_PU

        band = (comp.gate_band_pu if comp.gate_band_pu is not None else GATE_BAND_PU) * f1
    out = []
    demodulated = comp.input == "demodulated"
    if demodulated:
        out.append((key, f1))
    gating = comp.gating if comp.gating is not None else demodulated
    if gating and band > 0.0:
        out += [(key, n * f1) for n in HARMONICS[1:]]
    return out


def check_whole_injection_periods(
    comp: CompensatorSettings, inj: InjectionSettings, Ts: float, r=None
) -> None:
    """Refuse a decision period that does not hold a whole number (>= 1) of periods of every
    injection frequency in use (:func:`injection_frequencies_in_use`): the detected e_d0 would
    carry a ripple at the injection frequency instead of its mean.

    Raises
    ------
    ConfigError
        Naming the frequency (``compensator.period_s`` when it is the period that was set).
    """
    n_comp = decision_period_steps(comp, inj, Ts, r)
    T = n_comp * Ts
    for key, f in injection_frequencies_in_use(comp, inj, r):
        cycles = T * f
        if cycles < 1.0 - 1e-6 or abs(cycles - round(cycles)) > 1e-6 * max(cycles, 1.0):
            field = "compensator.period_s" if comp.period_s is not None else key
            raise ConfigError(
                field,
                f"the compensator period ({T:g} s, {n_comp} control periods) must hold a whole "
                f"number of periods of {f:g} Hz (got {cycles:g}), the injection frequency or a "
                "harmonic of it in the gating's schedule",
            )


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
}


def _compensator_start(data: dict):
    comp = data.get("compensator")
    return comp.get("t_on_s", 0.0) if isinstance(comp, dict) else 0.0


#: The values of a replaced key that ask for what its rule does (a scenario written out in
#: full by an earlier release states every key): dropped without a warning.
_ASKS_FOR_THE_RULE = {
    ("injection", "t_on_s"): lambda data, v: v == _compensator_start(data),
    ("compensator", "average"): lambda data, v: v is True,
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
