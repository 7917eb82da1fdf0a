"""The scenario's checks that reach across sections and into the machine.

Kept beside :class:`~imdrive.config.scenario.Scenario`, which calls them while it validates:
the defaults that follow the machine (:func:`machine_defaults`), the warnings for absolute
values far from this machine (:func:`per_unit_warnings`), and the plug-in estimators'
settings (:func:`plugin_rules`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

from imdrive.config.compensator import check_whole_injection_periods
from imdrive.config.overrides import _to_plain
from imdrive.config.perunit import resolve  # noqa: F401  (for callers' convenience)
from imdrive.config.plugins import PluginSettings, module_spec_of
from imdrive.config.r2_laws import FUZZY_LAWS, R2_LAW_SETTINGS
from imdrive.config.registry import ESTIMATOR_SETTINGS, package_sections
from imdrive.config.validation import validate
from imdrive.errors import ConfigError, ConfigWarning

#: sections only a field-oriented drive reads (``[drive] mode = "vector"``); the estimators'
#: own sections (``[mras]``, ``[ekf]`` ...) are added by :func:`vector_only_sections`
VECTOR_ONLY = (
    "control",
    "estimator",
    "controller_model",
    "flux_injection",
    "compensator",
    "injection",
)


def vector_only_sections() -> tuple[str, ...]:
    """The sections an open-loop drive ignores: :data:`VECTOR_ONLY` and each estimator's."""
    from imdrive.config.r2_laws import law_sections  # noqa: F811

    return (*VECTOR_ONLY, *package_sections(), *law_sections())


def drive_mode_given(data: dict) -> None:
    """A scenario file without ``[drive] mode`` runs open loop (the default, kept for the
    files that rely on it); one that nevertheless sets keys of a section only vector control
    reads (``[control]``, ``[estimator]``, ``[compensator]`` ...) most likely meant a
    field-oriented drive, and those keys are ignored: a deprecation warning naming them (such
    a file will be refused in a later release; it still runs open loop as before).

    An explicit ``mode = "open-loop"`` is the user's choice and passes (the console's closing
    line says that [control] and the estimator are unused).
    """
    drive = data.get("drive")
    if drive is not None and (not isinstance(drive, dict) or "mode" in drive):
        return  # a mode given (or a [drive] of the wrong type, which validation names)
    given = [k for k in vector_only_sections() if isinstance(data.get(k), dict) and data[k]]
    if given:
        names = ", ".join(f"[{k}]" for k in given)
        rule = (
            f"not given, so the drive runs open loop and ignores {names}, which only vector "
            'control reads: add [drive] mode = "vector" (field-oriented control), or mode = '
            '"open-loop" to run open loop without them (deprecated: a file like this one will '
            "be refused in a later release)"
        )
        warnings.warn(ConfigWarning("drive.mode", rule), stacklevel=4)


def machine_defaults(sc) -> None:
    """Defaults that follow the machine, filled in (and derived again when the machine
    changes): the DC link from the rated voltage. An explicit DC link that cannot reach
    the rated voltage is refused below half of it, else warned about."""
    inv = sc.inverter
    V_rated = sc.machine.rated_voltage_V
    if inv.Vdc_V is None or getattr(inv, "_Vdc_V_auto", False):
        inv = replace(inv, Vdc_V=V_rated * math.sqrt(2.0))
        object.__setattr__(inv, "_Vdc_V_auto", True)
        object.__setattr__(sc, "inverter", inv)
        return
    reach = inv.Vdc_V / math.sqrt(2.0)  # the line voltage the SVM's linear range reaches
    if reach < 0.5 * V_rated:
        raise ConfigError(
            "inverter.Vdc_V",
            f"{inv.Vdc_V:g} V reaches {reach:.0f} V line-to-line, less than half of "
            f"machine.rated_voltage_V = {V_rated:g} V: leave Vdc_V unset (√2 × the rated "
            "voltage) or raise it",
        )
    if reach < 0.98 * V_rated:
        warnings.warn(
            ConfigWarning(
                "inverter.Vdc_V",
                f"{inv.Vdc_V:g} V reaches {reach:.0f} V line-to-line, below "
                f"machine.rated_voltage_V = {V_rated:g} V: the drive is voltage-limited "
                f"from about {100 * reach / V_rated:.0f} % of base speed",
            ),
            stacklevel=2,
        )


def per_unit_warnings(sc, r) -> None:
    """A machine-dependent setting given as an absolute value far from what suits this
    machine (typically a value tuned for another machine) is warned about, one line each."""
    comp, inj, m = sc.compensator, sc.injection, sc.machine
    notes = []
    absolute_step = comp.G_CR_ohm is not None and comp.G_CR_pu is None
    if comp.enabled and absolute_step and not 1e-4 <= r.G_CR / r.R2_hat <= 0.2:
        notes.append(
            (
                "compensator.G_CR_ohm",
                f"{r.G_CR:g} ohm is {100 * r.G_CR / r.R2_hat:.3g} % of the initial R̂2 "
                f"({r.R2_hat:.3g} ohm) per step: set compensator.G_CR_pu instead",
            )
        )
    absolute = comp.R2_min_ohm is not None or comp.R2_max_ohm is not None
    if comp.enabled and absolute and not r.R2_min <= m.R2_ohm <= r.R2_max:
        notes.append(
            (
                "compensator.R2_min_ohm",
                f"the clamps [{r.R2_min:.3g}, {r.R2_max:.3g}] ohm exclude the machine's R2 = "
                f"{m.R2_ohm:.3g} ohm, so R̂2 cannot reach it: set R2_min_ratio/R2_max_ratio",
            )
        )
    i_m = m.rated_flux_Wb / m.M_H
    if inj.amplitude_pu is None and r.inj_amp > 0.0 and not 0.01 <= r.inj_amp / i_m <= 0.3:
        notes.append(
            (
                "injection.amplitude_A",
                f"{r.inj_amp:g} A is {100 * r.inj_amp / i_m:.3g} % of the rated magnetising "
                f"current {i_m:.3g} A: set injection.amplitude_pu instead",
            )
        )
    est = sc.estimator
    for key, value, plant in (
        ("R1_ohm", est.R1_ohm, m.R1_ohm),
        ("R2_ohm", est.R2_ohm, m.R2_ohm),
        ("M_H", est.M_H, m.M_H),
    ):
        if value is not None and not 0.5 <= value / plant <= 2.0:
            notes.append(
                (
                    f"estimator.{key}",
                    f"{value:g} is {value / plant:.3g} x the machine's {plant:.4g}: a "
                    f"starting value for another machine? set estimator.{key.split('_')[0]}"
                    "_ratio instead",
                )
            )
    notes += profile_time_notes(sc)
    for field_, rule in notes:
        warnings.warn(ConfigWarning(field_, rule), stacklevel=4)


#: rotor time constants of magnetisation before the speed reference may move (95 % of the flux)
MAGNETISE_T2 = 3.0


def profile_time_notes(sc) -> list[tuple[str, str]]:
    """The times of a field-oriented drive's speed reference checked against the machine,
    where the drive's own sequencing (:mod:`imdrive.config.sequence`) is switched off.

    A profile's times are absolute seconds; they suit a machine when

    * the speed reference first moves after :data:`MAGNETISE_T2` rotor time constants
      ``T2 = L2 / R2`` (the rotor flux at 95 % of its reference): the drive premagnetises that
      long by itself (``control.premagnetise_T2``), so this is checked only when the scenario
      shortens its premagnetisation;
    * no ramp asks more than the rated torque for the acceleration alone:
      ``J |dw/dt| <= T_rated``, i.e. a ramp from 0 to rated speed lasts at least the
      mechanical time constant ``J w_rated / T_rated``: the drive follows a ramp too steep for
      its torque limit at the limit (``control.ramp_torque_limit``), so this is checked only
      when that is off.

    Table IV's presets meet both (first move at 0.5 s >= 3 T2 = 0.26 s; 0 -> 1000 rpm in 1 s
    asks 7.2 N m of the 12 N m rated torque). A scenario whose times would suit Table IV but
    break a rule on its own machine (a preset with ``[machine]`` replaced) is warned of, with
    the time this machine needs; times that are short for Table IV too are the scenario's
    choice (a deliberately fast test) and pass silently.
    """
    m = sc.machine
    ctl = sc.control
    if sc.drive.mode != "vector":
        return []
    if ctl.premagnetise_T2 >= MAGNETISE_T2 and ctl.ramp_torque_limit:
        return []
    from imdrive.config.machine import machine_preset

    reference = machine_preset("paper-table-iv")
    if m == reference:
        return []
    if profile_time_notes_for(sc, reference):  # too short for Table IV as well
        return []
    return profile_time_notes_for(sc, m)


def profile_time_notes_for(sc, m) -> list[tuple[str, str]]:
    """The notes of :func:`profile_time_notes` for machine ``m`` (whatever ``sc``'s)."""
    from imdrive.config.profile_units import stated_speed_ref_rpm

    out = []
    try:
        pts = stated_speed_ref_rpm(sc).points
    except ConfigError:  # a per-unit profile on a machine without a rated point
        return out
    key = "control.speed_ref_pu" if sc.control.speed_ref_pu is not None else "control.speed_ref_rpm"
    T2 = m.L2_H / m.R2_ohm
    starts = [t0 for (t0, v0), (_, v1) in zip(pts, pts[1:], strict=False) if v1 != v0]
    if starts and sc.control.premagnetise_T2 < MAGNETISE_T2:
        t_first = starts[0]
        if t_first < MAGNETISE_T2 * T2:
            out.append(
                (
                    key,
                    f"moves at t = {t_first:g} s, before the rotor is magnetised: 3 rotor time "
                    f"constants of this machine are {MAGNETISE_T2 * T2:.3g} s "
                    f"(control.premagnetise_T2 = {sc.control.premagnetise_T2:g} shortens the "
                    "drive's own premagnetisation)",
                )
            )
    if sc.control.ramp_torque_limit:
        return out
    from imdrive.config.machine import rated_point

    try:
        T_rated = rated_point(m).torque_Nm
    except ConfigError:
        return out
    for (t0, v0), (t1, v1) in zip(pts, pts[1:], strict=False):
        need = m.J_kgm2 * abs(v1 - v0) * math.pi / 30.0 / T_rated
        if not need < 1e6:  # beyond any machine: left to the checks of the derived quantities
            break
        if t1 > t0 and need > t1 - t0:
            out.append(
                (
                    key,
                    f"the ramp {v0:g} -> {v1:g} rpm over {t1 - t0:g} s asks more than the rated "
                    f"torque {T_rated:.3g} N m to accelerate J = {m.J_kgm2:g} kg m^2: give it "
                    f"at least {need:.3g} s (control.ramp_torque_limit = false: the drive does "
                    "not limit it)",
                )
            )
            break
    return out


def _plugin_settings_class(name: str):
    """The settings class of the plug-in estimator or plug-in R2 law ``name``, or None."""
    cls = ESTIMATOR_SETTINGS.get(name)
    if cls is not None:
        return cls if cls.estimator_section is None else None
    cls = R2_LAW_SETTINGS.get(name)
    return cls if cls is not None and cls.law_section is None else None


def plugin_rules(sc) -> None:
    """Each ``[plugins.settings.NAME]`` table valid for its plug-in estimator's or R2 law's
    settings class (stored back with its defaults filled in); the module of a plug-in
    estimator or law in use listed in ``plugins.modules``, so a rerun or a worker process
    imports it again."""
    from imdrive.config.plugins import looked_past

    tables = {}
    for name, table in sc.plugins.settings.items():
        cls = _plugin_settings_class(name)
        if cls is None and looked_past():  # shown, not run: left as given
            tables[name] = table
            continue
        if cls is None:
            known = [n for n, c in ESTIMATOR_SETTINGS.items() if c.estimator_section is None]
            known += [n for n, c in R2_LAW_SETTINGS.items() if c.law_section is None]
            raise ConfigError(
                f"plugins.settings.{name}",
                f"no plug-in estimator or R2 law of that name is registered (plug-ins: {known})",
            )
        tables[name] = _to_plain(validate(cls, table, f"plugins.settings.{name}"))
    modules = list(sc.plugins.modules)
    for used in (sc.control.speed_feedback, sc.compensator.step_law):
        cls = _plugin_settings_class(used)
        spec = module_spec_of(cls) if cls is not None else None
        if spec is not None and spec not in modules:
            modules.append(spec)
    if tables != sc.plugins.settings or modules != list(sc.plugins.modules):
        object.__setattr__(sc, "plugins", PluginSettings(modules=tuple(modules), settings=tables))


#: The ``[compensator]`` keys of the paper's fuzzy law (the table's scaling and step), which
#: the model-based law (``step_law = "kalman"``) does not read.
FUZZY_LAW_KEYS = (
    "gain_E_per_Wb", "gain_E_pu", "G_CR_ohm", "G_CR_pu", "table",
)  # fmt: skip


def law_keys_unread(sc) -> None:
    """A warning per key of an R2 law not selected, set away from its default: the fuzzy
    law's keys under any other law (the model-based laws have no table and no output level;
    ``[kalman]`` holds the Kalman law's settings, ``[plugins.settings.NAME]`` a plug-in's), and
    ``[kalman]``'s under any law but ``"kalman"``; and one when a model-based law runs
    without the injection, whose flux response is its only measurement of R2.
    """
    comp = sc.compensator
    law = comp.step_law
    if comp.enabled and law not in FUZZY_LAWS:
        if not (sc.injection.amplitude_pu or sc.injection.amplitude_A):
            why = (
                f'"{law}" measures R2 from the injection\'s flux response, and the injection '
                "is off (injection.amplitude_pu): R2_hat is not tracked"
            )
            warnings.warn(ConfigWarning("compensator.step_law", why), stacklevel=4)
    unread = [] if law in FUZZY_LAWS else [("compensator", FUZZY_LAW_KEYS)]
    if law != "kalman":
        unread.append(("kalman", tuple(sc.kalman.__dataclass_fields__)))
    for section, keys in unread:
        given = getattr(sc, section)
        defaults = type(given)()
        if section == "kalman":
            why = f'has no effect: compensator.step_law is "{law}", not "kalman"'
        elif law == "kalman":
            why = (
                'has no effect with step_law = "kalman": the model-based law reads its '
                "settings from [kalman] (noise_pu, drift_pu)"
            )
        else:
            why = f'has no effect with step_law = "{law}": only the paper\'s table law reads it'
        for key in keys:
            if getattr(given, key) != getattr(defaults, key):
                warnings.warn(ConfigWarning(f"{section}.{key}", why), stacklevel=4)


def tracking_end(sc, r) -> None:
    """``simulation.tracking_windows``: ``t_end_s`` is ``compensator.t_on_s`` plus that many
    decision windows of the compensator (``r.n_comp`` control periods each), counted in
    control periods; with the compensator off too (a scenario that switches it off runs as
    long as the one that tracks)."""
    sim = sc.simulation
    if sim.tracking_windows is None:
        return
    Ts = sim.Ts_s
    n = round(sc.compensator.t_on_s / Ts) + sim.tracking_windows * int(r.n_comp)
    sim = replace(sim, t_end_s=n * Ts)
    object.__setattr__(sim, "_t_end_s_auto", True)
    object.__setattr__(sc, "simulation", sim)


def compensator_rules(sc) -> None:
    """The R̂2 clamps in order, given or default (one given clamp against the other's
    default: ``R2_min_ohm`` above the default ``R2_max_ohm`` made R̂2 jump); the decision
    period and the injection against the run and the machine."""
    comp = sc.compensator
    r = resolve(sc)
    tracking_end(sc, r)
    R2h, lo, hi = r.R2_hat, r.R2_min, r.R2_max
    if not lo < hi:
        field = (
            "compensator.R2_min_ohm" if comp.R2_min_ohm is not None else ("compensator.R2_max_ohm")
        )
        raise ConfigError(
            field,
            f"the clamps of R̂2 must satisfy R2_min_ohm < R2_max_ohm (got {lo:g} >= {hi:g}; "
            f"an unset clamp is 0.5 or 2 × the initial R̂2 = {R2h:g} ohm)",
        )
    Ts = sc.simulation.Ts_s
    inj = sc.injection
    # no division: a tiny product must not divide
    if inj.frequency_Hz is not None and inj.frequency_Hz * Ts < 0.5e-9:
        raise ConfigError("injection.frequency_Hz", "has a period of more than 2e9 periods")
    check_whole_injection_periods(comp, inj, Ts, r)
    i_rated = sc.machine.rated_current_A
    if r.inj_amp > i_rated:
        raise ConfigError(
            "injection.amplitude_pu" if inj.amplitude_pu is not None else "injection.amplitude_A",
            f"must be <= the machine's rated peak current {i_rated:.3g} A (a persistent "
            f"excitation is a small perturbation of the flux current; got {r.inj_amp:g} A)",
        )
    law_keys_unread(sc)
    sc._per_unit_warnings(r)
