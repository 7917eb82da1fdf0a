"""The one resolver of the settings whose unset value depends on the rest of the scenario.

A setting such as ``control.field_weakening`` or ``sensor.adc_range_A`` has no fixed default:
unset, it follows the machine (its rated speed, current, rotor corner) or the other settings
(the speed profile, the estimator). Each such setting is one :class:`Derived` entry of
:data:`DERIVED`, which holds

- ``rule``: what the unset value is, in words. The setting declares ``derived=True``
  (:func:`imdrive.config.validation.setting`) and docs/scenarios.md prints this rule as its
  default (:func:`rule`), so the text is written here once;
- ``value(sc)``: the value in effect in scenario ``sc``, the set one or the rule's;
- ``applies(sc)``: whether the setting acts in ``sc`` at all (the compensator's gains only with
  the compensator on, for instance).

Who reads it:

- ``run/blocks.py`` builds the drive's records from :func:`in_effect`;
- ``imdrive show --all`` and ``summary.json``'s ``"resolved"`` list :func:`derived_defaults`
  (:func:`imdrive.config.resolved.resolved_defaults`);
- a test checks that every entry's record field equals its value in every preset
  (``tests/config/test_defaults.py``).

The per-unit pairs (an absolute key and its per-unit twin, ``compensator.G_CR_ohm`` and
``G_CR_pu``) are turned into SI values by :func:`imdrive.config.perunit.resolve`; the entries
of those keys read them there. The estimators in modules of their own register their
section's entries beside their settings (:func:`register_derived`: ``[afo]``, ``[ekf]``), so
this module imports nothing of the config at import time, and each value function imports
the rule it calls (the import-cycle test, tests/package/test_layers.py, holds it to that).

Not here: the drive's sequencing (the speed and load profiles from per-unit, the
premagnetisation's delay, the torque-limited ramps), which is not one setting's default but
the profiles the kernels follow, resolved once by :func:`imdrive.config.sequence.sequence`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


def _vector(sc) -> bool:
    return sc.drive.mode == "vector"


def _mras(sc) -> bool:
    return _vector(sc) and sc.control.speed_feedback == "mras"


def _compensator(sc) -> bool:
    return _vector(sc) and sc.compensator.enabled


def _injection_frequency(sc) -> bool:
    from imdrive.config.perunit import resolve

    return _vector(sc) and resolve(sc).inj_amp > 0.0 and sc.injection.frequency_pu is None


def _always(sc) -> bool:
    return True


def _flux_injection(sc) -> bool:
    return _vector(sc) and sc.flux_injection.amplitude > 0.0


def _plant_thermal(sc) -> bool:
    return sc.plant.thermal.enabled


@dataclass(frozen=True)
class Derived:
    """A setting whose unset value depends on the scenario (module docstring).

    Attributes
    ----------
    key : str
        The dotted scenario key.
    rule : str
        What the unset value is, in words (docs/scenarios.md's default; it may hold the
        ``{placeholders}`` of :func:`imdrive.config.docs._derived_values`).
    value : callable
        ``value(sc)``: the value in effect in scenario ``sc``, in the key's unit.
    applies : callable
        ``applies(sc)``: whether the setting acts in ``sc``.
    """

    key: str
    rule: str
    value: Callable
    applies: Callable = _vector


def _field_weakening(sc):
    from imdrive.config.field_weakening import field_weakening_on

    return field_weakening_on(sc)


def _current_controller(sc):
    from imdrive.config.current_control import current_controller

    return current_controller(sc)


def _speed_gain_flux_scaling(sc):
    from imdrive.config.speed_gain import speed_gain_flux_scaling

    return speed_gain_flux_scaling(sc)


def _sign_band(sc):
    from imdrive.config.perunit import sign_band_A

    return sign_band_A(sc)


def _adc_range(sc):
    from imdrive.config.perunit import adc_range_A

    return adc_range_A(sc)


def _mras_bandwidth(sc):
    from imdrive.config.mras_bandwidth import mras_bandwidth_Hz

    return mras_bandwidth_Hz(sc)


def _r1_standstill_levels(sc):
    from imdrive.config.r1_standstill import r1_standstill_levels

    return r1_standstill_levels(sc)


def _acceleration_tracking(sc):
    from imdrive.config.mras_bandwidth import mras_type2
    from imdrive.config.perunit import resolve

    r = resolve(sc)
    return mras_type2(sc, sc.mras, (r.Ll2_hat + r.M_hat) / r.R2_hat)


def _mras_normalise(sc):
    from imdrive.config.mras_bandwidth import mras_normalise

    return mras_normalise(sc)


def _r1_max_freq(sc):
    from imdrive.config.mras_bandwidth import r1_max_freq_Hz

    return r1_max_freq_Hz(sc.mras, sc.machine.rated_frequency_Hz)


def _dead_time_compensation(sc) -> float:
    t = sc.control.dead_time_compensation_s
    return sc.inverter.dead_time_s if t is None else t


def _inverter_error_adaptation(sc) -> float:
    rate = sc.control.inverter_error_adaptation_per_s
    if rate is not None:
        return rate
    return 0.0 if sc.controller_model.uses_inverter_error else 1.0


def _gating(sc) -> bool:
    from imdrive.config.compensator import demodulated_input
    from imdrive.config.perunit import resolve

    g = sc.compensator.gating
    return g if g is not None else demodulated_input(sc.injection, resolve(sc))


def _flux_ref(sc) -> float:
    """The flux reference at the start (a profile when set: its first value), Wb."""
    given = sc.control.flux_ref_Wb
    return given.points[0][1] if given else sc.machine.rated_flux_Wb


def _saturation(n: int) -> Callable:
    """``Lm0`` (``n = 0``, H) or ``psi_sat`` (1, Wb) of the plant's magnetising curve."""

    def value(sc) -> float:
        return sc.plant.saturation.curve(sc.machine)[n]

    value.__qualname__ = f"_saturation_{n}"
    return value


def _saturating(sc) -> bool:
    return sc.plant.saturation.enabled


def _lost_control(sc):
    from imdrive.config.perunit import lost_control_rpm

    return lost_control_rpm(sc)


def _flux_injection_frequency(sc):
    from imdrive.config.scaled import flux_injection_frequency_Hz

    return flux_injection_frequency_Hz(sc)


def _plant_Rth(n: int) -> Callable:
    """The plant's stator (``n = 0``) or rotor (1) thermal resistance, K/W."""

    def value(sc):
        from imdrive.config.scaled import plant_thermal_resistances

        return plant_thermal_resistances(sc)[n]

    return value


def _resolved(field: str) -> Callable:
    """The value of ``field`` of :func:`imdrive.config.perunit.resolve` (a per-unit pair)."""

    def value(sc):
        from imdrive.config.perunit import resolve

        return float(getattr(resolve(sc), field))

    return value


_THE_PLANTS = "the plant's"

_ENTRIES = (
    Derived("estimator.R1_ohm", _THE_PLANTS, _resolved("R1_hat")),
    Derived("estimator.R2_ohm", _THE_PLANTS, _resolved("R2_hat")),
    Derived("estimator.M_H", _THE_PLANTS, _resolved("M_hat")),
    Derived("estimator.Ll1_H", _THE_PLANTS, _resolved("Ll1_hat")),
    Derived("estimator.Ll2_H", _THE_PLANTS, _resolved("Ll2_hat")),
    Derived(
        "control.flux_ref_Wb",
        "the machine's rated flux ({rated_flux_Wb} Wb for {preset})",
        _flux_ref,
    ),
    Derived("plant.saturation.Lm0_H", "M_H/rated_ratio", _saturation(0), _saturating),
    Derived(
        "plant.saturation.psi_sat_Wb",
        "psi_rated (rated_ratio/(1 - rated_ratio))^(1/S)",
        _saturation(1),
        _saturating,
    ),
    Derived(
        "compensator.gating",
        "on with the injection ([injection]), off without (the paper's e_d0 input)",
        _gating,
        _compensator,
    ),
    Derived(
        "control.dead_time_compensation_s",
        "inverter.dead_time_s (perfect knowledge)",
        _dead_time_compensation,
    ),
    Derived(
        "control.inverter_error_adaptation_per_s",
        "1 with the assumed dead-time feed-forward; 0 with a commissioned inverter-error table "
        "([controller_model]: measured, it has little left to learn, and on the realistic "
        "drive the scale's wander of a few % cost the sliding-mode MRAS 1-2 rpm at 100-150 "
        "rpm)",
        _inverter_error_adaptation,
    ),
    Derived(
        "control.field_weakening",
        "on when the speed reference reaches the speed where the rated torque at rated flux "
        "needs more than field_weakening_voltage of Vdc/√3 (config/field_weakening.py), else off",
        _field_weakening,
    ),
    Derived(
        "control.current_controller",
        '"imc" with field_weakening on where the speed reference\'s electrical speed exceeds '
        "half the current loop's bandwidth (1.74 x the rated speed of Table IV at 200 Hz; "
        'config/current_control.py), "pi" otherwise',
        _current_controller,
    ),
    Derived(
        "control.speed_gain_flux_scaling",
        "on with field_weakening on and a sensorless speed_feedback, else off",
        _speed_gain_flux_scaling,
    ),
    Derived(
        "control.current_limit_A",
        "1.5 × the rated peak current, √2 × the nameplate's rms current "
        "({current_limit_A} A for {preset})",
        _resolved("current_limit_A"),
    ),
    Derived(
        "simulation.divergence_current_A",
        "70 × the rated peak current ({divergence_current_A} A for {preset})",
        _resolved("divergence_current_A"),
        _always,
    ),
    Derived(
        "control.speed_bandwidth_Hz",
        "5 Hz, raised for a machine whose rated torque would pull the speed down by more than "
        "5 % of its rated speed in a rated-load step (config/perunit.py speed_bandwidth_Hz; at "
        "most a tenth of current_bandwidth_Hz)",
        _resolved("speed_bandwidth_Hz"),
    ),
    Derived(
        "simulation.divergence_speed_rpm",
        "20000/1800 (about 11) × the machine's synchronous speed: 20000 rpm on Table IV",
        _resolved("divergence_speed_rpm"),
        _always,
    ),
    Derived(
        "simulation.lost_control_rpm",
        "twice the machine's rated slip speed, at least 1 % of its rated speed (158 rpm on "
        "Table IV)",
        _lost_control,
    ),
    Derived(
        "inverter.sign_band_A",
        "Table IV's 0.2 A scaled by the machine's rated peak current (0.0174 × it; "
        "config/perunit.py sign_band_A)",
        _sign_band,
        _always,
    ),
    Derived(
        "sensor.adc_range_A",
        "Table IV's 50 A scaled by the machine's rated peak current (4.36 × it; "
        "config/perunit.py adc_range_A)",
        _adc_range,
        _always,
    ),
    Derived(
        "mras.bandwidth_Hz",
        "20 Hz, at least 4 times the speed loop's bandwidth "
        "(imdrive.config.mras_bandwidth.mras_bandwidth_Hz)",
        _mras_bandwidth,
    ),
    Derived(
        "mras.R1_standstill_levels",
        "2 where the controller compensates its inverter's error, else 1",
        _r1_standstill_levels,
    ),
    Derived(
        "mras.acceleration_tracking",
        "on when the type-1 lag at the machine's rated acceleration exceeds half the rotor's "
        "corner frequency 1/T2 (config/mras_type.py mras_ramp_lag_pu), and when the speed "
        "reference goes above 1.1 x the rated speed with field weakening on "
        "(mras_type2_for_field_weakening)",
        _acceleration_tracking,
        _mras,
    ),
    Derived(
        "mras.normalise",
        "on with control.field_weakening (set or by default), else off",
        _mras_normalise,
        _mras,
    ),
    Derived(
        "mras.R1_max_freq_Hz",
        "R1_max_freq_pu × the rated frequency",
        _r1_max_freq,
        _mras,
    ),
    Derived(
        "flux_injection.frequency_Hz",
        "Table IV's 2 Hz scaled by the machine's rotor corner R2/(2π L2) (1.098 × it; "
        "config/scaled.py flux_injection_frequency_Hz)",
        _flux_injection_frequency,
        _flux_injection,
    ),
    Derived(
        "plant.thermal.Rth1_K_per_W",
        "Table IV's 0.4 K/W scaled by 1 / the rated stator copper losses "
        "(config/scaled.py plant_thermal_resistances)",
        _plant_Rth(0),
        _plant_thermal,
    ),
    Derived(
        "plant.thermal.Rth2_K_per_W",
        "Table IV's 0.4 K/W scaled by 1 / the rated rotor copper losses "
        "(config/scaled.py plant_thermal_resistances)",
        _plant_Rth(1),
        _plant_thermal,
    ),
    Derived(
        "compensator.R2_min_ohm",
        "0.5 × the initial R̂2",
        _resolved("R2_min"),
        _compensator,
    ),
    Derived(
        "compensator.R2_max_ohm",
        "2 × the initial R̂2",
        _resolved("R2_max"),
        _compensator,
    ),
    Derived(
        "compensator.G_CR_ohm",
        "the paper's 0.001 on Table IV scaled by the machine's R2",
        _resolved("G_CR"),
        _compensator,
    ),
    Derived(
        "compensator.gain_E_per_Wb",
        "the paper's 1e6 on Table IV scaled by 1/ψ_rated (config/compensator_gains.py)",
        _resolved("gain_E"),
        _compensator,
    ),
    Derived(
        "compensator.gate_speed_rpm",
        "1 rpm on Table IV scaled by the rated slip speed (0.0126 × it)",
        _resolved("gate_speed_rpm"),
        _compensator,
    ),
    Derived(
        "compensator.gate_iq_A",
        "0.3 A on Table IV scaled by machine.rated_current_A",
        _resolved("gate_iq_A"),
        _compensator,
    ),
    Derived(
        "compensator.gate_band_Hz",
        "0.75 of the first injection frequency (1.5 Hz of Table IV's 2 Hz)",
        _resolved("gate_band"),
        _compensator,
    ),
    Derived(
        "injection.frequency_Hz",
        "Table IV's 2 Hz scaled by the machine's rotor corner R2/(2π L2), to whole control "
        "periods (config/compensator_gains.py injection_frequency_Hz)",
        _resolved("inj_f1"),
        _injection_frequency,
    ),
)

#: dotted key -> its :class:`Derived` entry: every setting whose unset value depends on the
#: scenario, resolved here and nowhere else (the package's below; an estimator's own section
#: registers its entries beside its settings class: :func:`register_derived`).
DERIVED: dict[str, Derived] = {d.key: d for d in _ENTRIES}


def register_derived(*entries: Derived) -> None:
    """Add the derived settings of a section that lives in a module of its own (an estimator's
    ``[afo]``, ``[ekf]``; not a plug-in's ``[plugins.settings.<name>]``, whose settings its
    own ``records`` resolves): its settings declare ``derived=True`` and the module
    registers one :class:`Derived` entry for each, so the records, ``show --all``,
    ``summary.json`` and the docs find them here as the package's.

    Raises
    ------
    ValueError
        A key already registered by another entry.
    """
    for d in entries:
        if d.key in DERIVED and _origin(DERIVED[d.key]) != _origin(d):
            raise ValueError(f"{d.key}: a derived default is already registered")
        DERIVED[d.key] = d


def _origin(d: Derived) -> tuple:
    """What makes two entries one (a module imported again registers its entries again)."""
    f = d.value
    return d.key, d.rule, getattr(f, "__module__", None), getattr(f, "__qualname__", None)


def uses_estimator(name: str) -> Callable:
    """``applies`` of an estimator's own settings: the vector drive with that estimator."""

    def applies(sc) -> bool:
        return _vector(sc) and sc.control.speed_feedback == name

    return applies


def rule(key: str) -> str:
    """The rule of ``key``'s unset value (a setting's ``default_doc``)."""
    return DERIVED[key].rule


def in_effect(sc, key: str):
    """The value of setting ``key`` in effect in scenario ``sc``: the set one, or its rule's.

    Raises
    ------
    KeyError
        ``key`` is not a setting of :data:`DERIVED`.
    """
    memo = getattr(sc, "_in_effect", None)  # a scenario is frozen: each value is computed once
    if memo is None:
        memo = {}
        try:
            object.__setattr__(sc, "_in_effect", memo)
        except (AttributeError, TypeError):  # not a Scenario (a stand-in in a test): no memo
            return DERIVED[key].value(sc)
    if key not in memo:
        memo[key] = DERIVED[key].value(sc)
    return memo[key]


def derived_defaults(sc) -> dict[str, object]:
    """Dotted key -> value in ``sc`` of every setting of :data:`DERIVED` that acts in it (set
    or not: the callers keep the unset ones)."""
    return {key: in_effect(sc, key) for key, d in DERIVED.items() if d.applies(sc)}
