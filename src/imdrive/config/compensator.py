"""Settings of the fuzzy rotor-resistance compensator and of its persistent excitation
(sections ``[compensator]``, ``[injection]``).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import AfterValidator, model_validator

from imdrive.config import compensator_deprecated  # noqa: F401  (the deprecated keys register)
from imdrive.config.r2_kalman import (  # noqa: F401  (the law registers)
    THERMAL_ALPHA_PER_K,
    THERMAL_RISE_K,
    KalmanLawSettings,
)
from imdrive.config.r2_laws import law_names
from imdrive.config.validation import Bool, Float, Str, setting, settings
from imdrive.errors import ConfigError

#: The gating's frequency schedule: these multiples of the injection frequency f. Near the
#: stator frequency the lowest of them at least ``compensator.gate_band_pu`` f from it (and,
#: where the detection forms its own flux error, from its filter's corner) is injected
#: (kernels/gating.py). Whole multiples, a decision window of whole periods of f holds
#: whole periods of each. Every preset and study used 1, 2, 3 f when they could be set apart
#: (``injection.frequency2_*``, ``frequency3_*``: deprecated).
HARMONICS = (1, 2, 3)


def _known_law(name: str) -> str:
    """A registered R2 law, the package's or a plug-in's
    (:func:`imdrive.config.r2_laws.law_names`)."""
    if name not in law_names():
        from imdrive.config.plugins import looked_past

        if looked_past():  # shown, not run: the unimported plug-in may define it
            return name
        raise ConfigError("", "must be one of " + ", ".join(repr(n) for n in law_names()))
    return name


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
    default to 0.5 and 2 times the initial estimate. The input is e_d0 detected synchronously
    with the injection whenever it runs, else e_d0 itself, the paper's
    (:func:`demodulated_input`); the decision window is one injection period, or 10 ms without
    the injection (:func:`decision_period_steps`).

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
    gain_E_per_Wb: Annotated[
        Float | None,
        setting(
            "scaling of e_d0 before the 13-level quantiser (1e6: the paper's µWb thresholds)",
            "1/Wb",
            gt=0.0,
            derived=True,
        ),
    ] = None
    G_CR_ohm: Annotated[
        Float | None,
        setting(
            "change of R̂2 per output level and period",
            "ohm",
            ge=0.0,
            derived=True,
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
        setting("lower clamp of R̂2", "ohm", gt=0.0, derived=True),
    ] = None
    R2_max_ohm: Annotated[
        Float | None,
        setting("upper clamp of R̂2", "ohm", gt=0.0, derived=True),
    ] = None
    table: Annotated[
        Literal["paper", "rules"],
        setting('"paper": the printed Table III; "rules": compiled from the fitted rule base'),
    ] = "paper"
    gating: Annotated[
        Bool | None,
        setting(
            "freeze R̂2 during speed and load transients and in voltage saturation, and move "
            "the injection frequency away from the stator frequency (kernels/compensator.py)",
            derived=True,
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
            derived=True,
        ),
    ] = None
    gate_iq_A: Annotated[
        Float | None,
        setting(
            "gating: change of the period-mean iq* from one period to the next above which the "
            "period is a load transient",
            "A",
            gt=0.0,
            derived=True,
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
            "(0: never); where the R2 detection forms its own flux error (the observer, the "
            "EKF), at least the corner of its filter, [mras] wc_rad_s (kernels/gating.py)",
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
            derived=True,
        ),
    ] = None
    step_law: Annotated[
        Str,
        AfterValidator(_known_law),  # the paper's table and every registered law (r2_laws.py)
        setting(
            '"table": R̂2 changes by G_CR_ohm × the table\'s level (the paper); "kalman": the '
            "detected error over its modelled response (the analytic sensitivity through the "
            "detection's filter), filtered by a Kalman filter on R2 "
            "and its drift rate (section [kalman], kernels/r2_kalman.py); the table's gains "
            'then have no effect. "adaptive" (deprecated) runs as "kalman"; or a law '
            "registered by a module of [plugins] modules (docs/architecture.md)"
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
            "config/perunit.py; 80 K: the class B limit of IEC 60034-1); times "
            "thermal_alpha_per_K, also the model-based law's prior (config/r2_kalman.py "
            "prior_pu)",
            "K",
            gt=0.0,
        ),
    ] = THERMAL_RISE_K
    thermal_alpha_per_K: Annotated[
        Float,
        setting(
            "thermal model: temperature coefficient of R2 (copper 0.00393, aluminium 0.00403); "
            "times thermal_rise_K, also the model-based law's prior",
            "1/K",
            gt=0.0,
        ),
    ] = THERMAL_ALPHA_PER_K

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

    ``amplitude_pu`` unset or 0 switches it off. While it runs the compensator feeds on e_d0
    detected synchronously with this sinusoid (:func:`demodulated_input`); its period must be
    a whole number of periods of every injection frequency it uses (the default compensator
    period is one; :func:`check_whole_injection_periods`).
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
            derived=True,
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
    headroom_voltage: Annotated[
        Float | None,
        setting(
            "estimation headroom: the peak voltage use per injection period (fraction of "
            "Vdc/√3) the field weakening holds while the injection runs, so near and above "
            "base speed the flux is lowered a few percent and the injection keeps its full "
            "amplitude, also in field weakening (kernels/compensator_range.py, "
            "headroom_weakening_input); the amplitude's back-off band sits above it "
            "(config/injection_backoff.py); needs control.field_weakening",
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
            "slip_coupling); matters at large slip (full load above base speed); faded in from "
            "0.3 of the rated stator frequency to 0.6 (run/compensator_blocks.py "
            "SLIP_DECOUPLING_FROM_PU)"
        ),
    ] = True


def injection_amplitude_given(inj) -> float:
    """The injection's amplitude as stated, in its own unit (per-unit or, deprecated, A): 0
    when neither ``amplitude_pu`` nor ``amplitude_A`` is set; whether it is on is its sign."""
    if inj.amplitude_pu is not None:
        return inj.amplitude_pu
    return inj.amplitude_A if inj.amplitude_A is not None else 0.0


def demodulated_input(inj, r=None) -> bool:
    """Whether the compensator's input is e_d0 detected synchronously with the injection: exactly
    when the injection runs (``compensator.input``, deprecated). Without the injection the
    detected product is zero and R̂2 never moves; with it, e_d0 itself carries the injection's
    ripple, which a 10 ms window does not average out: the paper's e_d0 is its input without
    the injection. Every preset, sweep and study paired them so. ``r``: the resolved values."""
    return (injection_amplitude_given(inj) if r is None else r.inj_amp) > 0.0


def _first_frequency(inj) -> float:
    """The injection frequency without the scenario's machine (no resolved values at hand):
    as given, else Table IV's default."""
    from imdrive.config.compensator_gains import INJECTION_TABLE_IV_HZ

    return inj.frequency_Hz if inj.frequency_Hz is not None else INJECTION_TABLE_IV_HZ


def decision_period_steps(
    comp: CompensatorSettings, inj: InjectionSettings, Ts: float, r=None
) -> int:
    """The compensator's decision period in control periods (at least one).

    One injection period with the injection (:func:`demodulated_input`): the shortest window
    that holds whole periods of it and of its harmonics (the synchronous detection's mean); else
    10 ms, the paper's e_d0 input (the paper gives none); rounded to whole control periods of
    ``Ts`` s (``compensator.period_s``, deprecated: a longer window bought nothing, see its
    note in :mod:`imdrive.config.compensator_deprecated`). ``r``: the scenario's per-unit
    values resolved (:func:`imdrive.config.perunit.resolve`), whose injection frequency is used
    when given.
    """
    if comp.enabled and demodulated_input(inj, r):
        period = 1.0 / (_first_frequency(inj) if r is None else r.inj_f1)
    else:
        period = 0.01
    return max(int(round(period / Ts)), 1)


def injection_frequencies_in_use(
    comp: CompensatorSettings, inj: InjectionSettings, r=None
) -> list[tuple[str, float]]:
    """``(key, Hz)`` of each injection frequency the compensator's decision period must hold
    whole periods of, so that the synchronous detection averages over whole periods.

    The injection frequency (the input is demodulated with it); with the gating's frequency schedule
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
    out = [(key, f1)]  # the input is demodulated with it (demodulated_input)
    gating = comp.gating if comp.gating is not None else True
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
        Naming the key that sets the injection frequency.
    """
    n_comp = decision_period_steps(comp, inj, Ts, r)
    T = n_comp * Ts
    for key, f in injection_frequencies_in_use(comp, inj, r):
        cycles = T * f
        if cycles < 1.0 - 1e-6 or abs(cycles - round(cycles)) > 1e-6 * max(cycles, 1.0):
            raise ConfigError(
                key,
                f"the compensator period ({T:g} s, {n_comp} control periods) must hold a whole "
                f"number of periods of {f:g} Hz (got {cycles:g}), the injection frequency or a "
                "harmonic of it in the gating's schedule",
            )
