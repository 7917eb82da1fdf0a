"""Nameplate and catalogue data -> T-equivalent circuit (an estimate, with its assumptions).

A motor's nameplate gives rated power ``P``, line voltage ``V``, frequency ``f``, poles,
speed ``n``, line current ``I``, power factor ``cos phi`` and efficiency ``eta``; a NEMA
nameplate adds the design letter (the leakage split) and the code letter (locked-rotor kVA
per hp); a catalogue adds the breakdown torque ratio ``T_bd / T_n`` and the starting current
ratio ``I_st / I_n``. :func:`estimate_circuit` estimates the single-cage T-circuit (``R1``,
``R2``, ``X1``, ``X2``, ``X_M``) that imdrive's plant model simulates:

``method="catalogue"`` (the one to use: :func:`estimate_circuit_catalogue`)
    Uses every figure given (equations and sources in
    :mod:`imdrive.analysis.nameplate_catalogue`): the efficiency through a loss split (core,
    friction and windage, stray load), so that ``R1`` is the stator's copper resistance; the
    rated point's power factor; the leakage from the breakdown torque when the catalogue gives
    it, else from the starting current, else from the NEMA code letter (G assumed, and said
    so). The plant carries no iron, friction or stray loss: loaded to rated torque it turns a
    little faster and draws a little less current than the nameplate, by the losses it does
    not carry (``rated_torque`` and ``rated_current`` residuals). Checked on published
    textbook circuits with their losses (:mod:`imdrive.studies.nameplate_published`).

``method="lee"`` (deprecated: :func:`estimate_circuit_lee`)
    The nameplate-only method of K. Lee, S. Frank, P. K. Sen et al., NAPS 2012
    (:mod:`imdrive.analysis.nameplate_lee`): the same loss split, the leakage from the
    locked-rotor current only (a breakdown torque is refused), the magnetising branch
    neglected at standstill.

``method="fit"`` (deprecated; the default of ``estimate_circuit`` when no method is named)
    A least-squares fit to the rated point and the breakdown torque that lumps every loss
    into ``R1`` (:mod:`imdrive.analysis.nameplate_fit`): it meets the rated current exactly,
    with an ``R1`` up to 2.5 times the stator's.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

from imdrive.analysis.circuit import equivalent_circuit
from imdrive.analysis.inertia import inertia_constant_s, inertia_problem, rotor_inertia_kgm2
from imdrive.analysis.nameplate_catalogue import catalogue_circuit
from imdrive.analysis.nameplate_fit import DEFAULT_BREAKDOWN_RATIO, fit_circuit
from imdrive.analysis.nameplate_lee import (
    CORE_LOSS_FRACTION,
    MECHANICAL_LOSS_FRACTION,
    NEMA_CODE_LETTERS,
    lee_circuit,
    locked_rotor_current_A,
)
from imdrive.config.machine import MachineParams
from imdrive.config.validation import FLOAT_MAX_MAGNITUDE, FLOAT_MIN_MAGNITUDE
from imdrive.errors import ConfigError, ConfigWarning, check_argument

#: the bound of every nameplate magnitude: the scenario's (imdrive.config.validation)
_MAGNITUDE = (FLOAT_MIN_MAGNITUDE, FLOAT_MAX_MAGNITUDE)
_UNITS = {"power_W": "W", "voltage_V": "V", "frequency_Hz": "Hz", "speed_rpm": "rpm",
          "current_A": "A"}  # fmt: skip

__all__ = [
    "DEFAULT_BREAKDOWN_RATIO",
    "DEFAULT_CODE_LETTER",
    "LEAKAGE_SPLIT",
    "METHODS",
    "Nameplate",
    "NameplateFit",
    "estimate_circuit",
    "estimate_circuit_catalogue",
    "estimate_circuit_lee",
]

#: The estimation methods of :func:`estimate_circuit` (module docstring); all but the first
#: are deprecated (a DeprecationWarning names it).
METHODS = ("catalogue", "lee", "fit")

#: Rated slip outside this range is suspicious (a ConfigWarning): large motors run at a few
#: tenths of a per cent, small ones at up to about 10 %.
SLIP_RANGE = (0.002, 0.10)

#: The options of the methods that split the losses (their loss fractions).
_LOSS_OPTIONS = ("core_loss_fraction", "mechanical_loss_fraction", "stray_loss_fraction")

#: NEMA code letter assumed by ``method="catalogue"`` and ``"lee"`` when the data give no
#: other leakage figure: G (5.6-6.3 kVA/hp, a locked-rotor current of about 6 times rated on
#: a typical design B machine). An assumption, reported as such.
DEFAULT_CODE_LETTER = "G"

#: X1 / (X1 + X2) by NEMA design letter (IEEE Std 112).
LEAKAGE_SPLIT = {"A": 0.5, "B": 0.4, "C": 0.3, "D": 0.5, "wound": 0.5}

#: Deprecated names -> (value, what replaced them): importable, with a DeprecationWarning.
_DEPRECATED = {
    "DEFAULT_INERTIA_CONSTANT_S": (
        0.5,
        "the inertia constant H = J w_m^2 / (2 P), s, that set a J the data do not give in "
        "imdrive 0.1; J now comes from the rotor's size "
        "(imdrive.analysis.inertia.rotor_inertia_kgm2)",
    ),
}


def __getattr__(name: str):
    if name in _DEPRECATED:
        value, what = _DEPRECATED[name]
        warnings.warn(f"{name} is deprecated: {what}", DeprecationWarning, stacklevel=2)
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class Nameplate:
    """Nameplate and catalogue data of a three-phase induction motor (SI; rpm for speed).

    Attributes
    ----------
    power_W : float
        Rated shaft power, W.
    voltage_V : float
        Rated line-to-line rms voltage, V.
    frequency_Hz : float
        Rated frequency, Hz.
    poles : int
        Number of poles (2 n_p).
    speed_rpm : float
        Rated speed, rpm (below ``120 f / poles``).
    current_A : float
        Rated line current, rms, A.
    power_factor : float
        Rated power factor, dimensionless.
    efficiency : float
        Rated efficiency, dimensionless.
    breakdown_torque_ratio : float or None
        Breakdown (pull-out) torque over rated torque, dimensionless.
    starting_current_ratio : float or None
        Locked-rotor current over rated current, dimensionless.
    leakage_split : float
        ``X1 / (X1 + X2)``, dimensionless (:data:`LEAKAGE_SPLIT`); freed when both the
        breakdown torque and the starting current are given.
    J_kgm2 : float or None
        Rotor inertia, kg m^2; ``None``: that of a rotor of this size,
        ``J = k_J (T_n / 1 N m)^a_J`` (:func:`~imdrive.analysis.inertia.rotor_inertia_kgm2`,
        imdrive's fit to catalogue motors). One more than 4 times off it is warned about.
    code_letter : str or None
        NEMA code letter (locked-rotor kVA per hp,
        :data:`~imdrive.analysis.nameplate_lee.NEMA_CODE_LETTERS`), used by ``method="lee"``
        when no starting current ratio is given.
    """

    power_W: float
    voltage_V: float
    frequency_Hz: float
    poles: int
    speed_rpm: float
    current_A: float
    power_factor: float
    efficiency: float
    breakdown_torque_ratio: float | None = None
    starting_current_ratio: float | None = None
    leakage_split: float = 0.5
    J_kgm2: float | None = None
    code_letter: str | None = None

    def __post_init__(self):
        for name in ("power_W", "voltage_V", "frequency_Hz", "speed_rpm", "current_A"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ConfigError(name, f"must be a finite number > 0, got {v!r}")
            if not _MAGNITUDE[0] <= v <= _MAGNITUDE[1]:  # the scenario's own bound
                unit = _UNITS[name]
                raise ConfigError(
                    name,
                    f"must be between {_MAGNITUDE[0]:g} and {_MAGNITUDE[1]:g} {unit} (got {v:g} "
                    f"{unit}): derived quantities would overflow or vanish",
                )
        if not (isinstance(self.poles, int) and 2 <= self.poles <= 1000 and self.poles % 2 == 0):
            raise ConfigError("poles", f"must be an even integer 2-1000, got {self.poles!r}")
        for name in ("power_factor", "efficiency"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and 0.01 <= v < 1):
                raise ConfigError(name, f"must be at least 0.01 and below 1, got {v!r}")
        for name, hi, what in (
            ("breakdown_torque_ratio", 20.0, "a breakdown torque at or below the rated torque"),
            ("starting_current_ratio", 50.0, "a starting current at or below the rated current"),
        ):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, int | float) and 1 < v <= hi):
                raise ConfigError(
                    name, f"must be > 1 and <= {hi:g} (finite), got {v!r} ({what} "
                    "contradicts the rating)" if isinstance(v, int | float) and v <= 1 else
                    f"must be > 1 and <= {hi:g} (finite), got {v!r}",
                )  # fmt: skip
        if self.J_kgm2 is not None and not (
            isinstance(self.J_kgm2, int | float)
            and math.isfinite(self.J_kgm2)
            and _MAGNITUDE[0] <= self.J_kgm2 <= _MAGNITUDE[1]
        ):
            raise ConfigError("J_kgm2", f"must be a finite number > 0, got {self.J_kgm2!r}")
        # the values against each other: the input power the plate implies against the rated
        # power (a real motor's are within a few per cent)
        implied = math.sqrt(3.0) * self.voltage_V * self.current_A
        implied *= self.power_factor * self.efficiency
        if not (implied < math.inf and 1.0 / 3.0 <= implied / self.power_W <= 3.0):
            raise ConfigError(
                "power_W",
                f"{self.power_W:.4g} W contradicts sqrt(3) V I cos phi eta = {implied:.4g} W "
                "(more than a factor of 3 apart): check the power, voltage, current, power "
                "factor and efficiency",
            )
        electric = math.sqrt(3.0) * self.voltage_V * self.current_A * self.power_factor
        if not electric > self.power_W:
            raise ConfigError(
                "current_A, power_factor",
                f"sqrt(3) V I cos phi = {electric:.5g} W of input is not above the rated output "
                f"{self.power_W:.5g} W (an efficiency of 1 or more): check the current, power "
                "factor and power",
            )
        if not 0.05 <= self.leakage_split <= 0.95:
            raise ConfigError("leakage_split", "must be within 0.05-0.95")
        n_sync = 120.0 * self.frequency_Hz / self.poles
        if not self.speed_rpm < n_sync:
            raise ConfigError(
                "speed_rpm", f"must be below the synchronous speed 120 f / poles = {n_sync:g} rpm"
            )
        if self.code_letter is not None and self.code_letter not in NEMA_CODE_LETTERS:
            raise ConfigError("code_letter", "must be a NEMA code letter A-V (not I, O, Q)")
        slip = 1.0 - self.speed_rpm / n_sync
        if not self.efficiency < 1.0 - slip:
            raise ConfigError(
                "efficiency",
                f"{self.efficiency:g} must be below 1 - slip = {1 - slip:.4g} (the rotor copper "
                "loss alone is slip x air-gap power)",
            )

    @property
    def slip(self) -> float:
        """Rated slip ``1 - n / n_sync``."""
        return 1.0 - self.speed_rpm * self.poles / (120.0 * self.frequency_Hz)

    @property
    def torque_Nm(self) -> float:
        """Rated torque ``P / (2 pi n / 60)``, N m."""
        return self.power_W / (self.speed_rpm * math.pi / 30.0)


@dataclass(frozen=True)
class NameplateFit:
    """The estimated circuit and how well it reproduces the data.

    Attributes
    ----------
    machine : MachineParams
        The estimated machine (circuit, nameplate fields, J).
    residuals : dict of str to float
        ``method="fit"``: relative error of each fitted quantity (``rated_R``, ``rated_X`` of
        the rated-point impedance over ``|Z_n|``; ``breakdown_torque``; ``starting_current``)
        and of the efficiency the circuit implies against the given one (``efficiency``).
        ``method="lee"``: the circuit's torque and current at the rated slip and voltage
        against the nameplate's (``rated_torque``, ``rated_current``).
    assumed : tuple of str
        What was assumed for want of data (empty when nothing was).
    method : str
        ``"fit"`` or ``"lee"`` (:data:`METHODS`).
    details : dict
        ``method="lee"``: the core-loss resistance ``RC_ohm`` the plant model does not
        carry, the locked-rotor current used (``locked_rotor_current_A``), the loss split
        (``P_in_W``, ``P_core_W``, ``P_mech_W``, ``P_stray_W``, ``P_scl_W``, ``P_rcl_W``,
        ``P_ag_W``) and the sweeps (``iterations``).
    """

    machine: MachineParams
    residuals: dict = field(default_factory=dict)
    assumed: tuple = ()
    method: str = "fit"
    details: dict = field(default_factory=dict)


def estimate_circuit(
    plate: Nameplate, description: str = "", method: str | None = None, **options
) -> NameplateFit:
    """Estimate the T-equivalent circuit from nameplate and catalogue data.

    Parameters
    ----------
    plate : Nameplate
        The data.
    description : str
        Text for the machine's ``description``.
    method : {"catalogue", "lee", "fit"} or None
        ``"catalogue"``: every figure given, R1 the stator's
        (:func:`estimate_circuit_catalogue`; the one to use). ``"lee"`` and ``"fit"`` are
        deprecated (a DeprecationWarning names the replacement). None: ``"fit"``, as before,
        with a DeprecationWarning (the default becomes ``"catalogue"`` in imdrive 0.3).
    **options
        ``"catalogue"`` and ``"lee"``: the loss fractions ``core_loss_fraction``,
        ``mechanical_loss_fraction``, ``stray_loss_fraction``.

    Returns
    -------
    NameplateFit
        The machine (validated :class:`~imdrive.config.machine.MachineParams`), the
        residuals and the assumptions made.

    Raises
    ------
    ConfigError
        Data no single-cage circuit can meet (naming the quantities).

    Warns
    -----
    ConfigWarning
        A rated slip outside :data:`SLIP_RANGE`; a given J more than
        :data:`~imdrive.analysis.inertia.INERTIA_WARN_FACTOR` times off a rotor of this size.
    DeprecationWarning
        ``method`` ``"lee"``, ``"fit"`` or not given.

    Notes
    -----
    The methods and their assumptions are in the module docstring.
    """
    if method is None or method in ("lee", "fit"):
        what = "no method (the default fit)" if method is None else f"method={method!r}"
        warnings.warn(
            f"estimate_circuit with {what} is deprecated: use method='catalogue' (every "
            "catalogue figure, R1 the stator's; the default from imdrive 0.3)",
            DeprecationWarning,
            stacklevel=2,
        )
    try:
        return _estimate_circuit(plate, description, method or "fit", **options)
    except (ArithmeticError, ValueError) as exc:  # extreme data overflow in the estimate
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(
            "nameplate",
            f"the circuit cannot be estimated from these values ({type(exc).__name__}: "
            f"{exc}): some are far outside a physical range",
        ) from None


def _estimate_circuit(plate, description, method, **options) -> NameplateFit:
    check_argument(plate, Nameplate, "plate", "a Nameplate (imdrive.analysis.nameplate)")
    check_argument(description, str, "description", "a str")
    if method not in METHODS:
        raise ConfigError("method", f"must be one of {', '.join(METHODS)}, got {method!r}")
    _warn_suspicious(plate)
    if method in ("catalogue", "lee"):
        extra = sorted(set(options) - set(_LOSS_OPTIONS))
        if extra:
            raise ConfigError(
                extra[0], f"not an option of {method} (it takes {', '.join(_LOSS_OPTIONS)})"
            )
        estimate = estimate_circuit_catalogue if method == "catalogue" else estimate_circuit_lee
        return estimate(plate, description, **options)
    if options:
        raise ConfigError("method", f"fit takes no options, got {', '.join(options)}")
    circuit, residuals, assumed = fit_circuit(plate)
    machine = _machine(plate, *circuit, description, assumed)
    return NameplateFit(machine=machine, residuals=residuals, assumed=tuple(assumed))


def _warn_suspicious(p: Nameplate) -> None:
    """A :class:`~imdrive.errors.ConfigWarning` for a rated slip outside :data:`SLIP_RANGE`
    and for a given J far from a rotor of this size
    (:func:`~imdrive.analysis.inertia.inertia_problem`)."""
    problem = None if p.J_kgm2 is None else inertia_problem(p.J_kgm2, p.power_W, p.speed_rpm)
    if problem is not None:
        warnings.warn(ConfigWarning("J_kgm2", problem), stacklevel=4)
    lo, hi = SLIP_RANGE
    if not lo <= p.slip <= hi:
        warnings.warn(
            ConfigWarning(
                "speed_rpm",
                f"rated slip {100 * p.slip:.3g} % is outside the usual {100 * lo:g}-"
                f"{100 * hi:g} %: check the speed (and the poles and frequency)",
            ),
            stacklevel=4,
        )


def _machine(p: Nameplate, R1, R2, X1, X2, XM, description: str, assumed: list) -> MachineParams:
    """The MachineParams of a circuit (ohm at the rated frequency) and its nameplate; J from
    the plate or, when it gives none, a rotor of its size (appended to ``assumed``)."""
    w_e = 2.0 * math.pi * p.frequency_Hz
    J = p.J_kgm2
    if J is None:
        J = rotor_inertia_kgm2(p.power_W, p.speed_rpm)
        H = inertia_constant_s(J, p.power_W, p.speed_rpm)
        assumed.append(
            f"J = {J:.3g} kg m^2 of a rotor of this size (inertia constant H = {H:.3g} s; "
            "imdrive.analysis.inertia, fitted to catalogue motors of 0.75-22 kW)"
        )
    return MachineParams(
        R1_ohm=R1,
        R2_ohm=R2,
        Ll1_H=X1 / w_e,
        Ll2_H=X2 / w_e,
        M_H=XM / w_e,
        pole_pairs=p.poles // 2,
        J_kgm2=J,
        rated_power_W=float(p.power_W),
        rated_voltage_V=float(p.voltage_V),
        rated_frequency_Hz=float(p.frequency_Hz),
        rated_speed_rpm=float(p.speed_rpm),
        rated_current_rms_A=float(p.current_A),
        rated_power_factor=float(p.power_factor),
        rated_efficiency=float(p.efficiency),
        description=description,
    )


def estimate_circuit_lee(
    plate: Nameplate,
    description: str = "",
    core_loss_fraction: float = CORE_LOSS_FRACTION,
    mechanical_loss_fraction: float = MECHANICAL_LOSS_FRACTION,
    stray_loss_fraction: float | None = None,
) -> NameplateFit:
    """Estimate the T-circuit by the nameplate-only method of Lee, Frank, Sen et al. (2012).

    Parameters
    ----------
    plate : Nameplate
        The data: power, voltage, frequency, poles, speed, power factor, efficiency and the
        leakage split (design letter); the locked-rotor current from
        ``starting_current_ratio`` (a catalogue's ``I_st / I_n``) if given, else from
        ``code_letter``, else :data:`DEFAULT_CODE_LETTER` is assumed. A breakdown torque
        ratio is not used (the method has no place for it: ``method="fit"`` has).
    description : str
        Text for the machine's ``description``.
    core_loss_fraction, mechanical_loss_fraction : float
        Core and friction-and-windage loss over the total loss ``P / eta - P``
        (defaults: the method's 0.12 and 0.14). A circuit known to carry copper losses only
        (as imdrive's library machines) has 0 and 0.
    stray_loss_fraction : float or None
        Stray-load loss over ``P``; None: IEEE Std 112's by rating
        (:func:`~imdrive.analysis.nameplate_lee.stray_loss_fraction`).

    Returns
    -------
    NameplateFit
        The machine (the method's circuit without its core-loss branch), and as residuals the
        plant circuit's relative error at the rated slip and voltage against the nameplate:
        ``rated_torque`` (``T_e / T_n - 1``: the friction and stray losses the plant does not
        carry), ``rated_current`` (``|I1| / I_n - 1``: the core-loss current it does not draw,
        and a nameplate current that differs from ``P / (sqrt 3 V eta cos phi)``);
        ``details`` holds the method's own circuit and loss split.

    Raises
    ------
    ConfigError
        Data the method cannot meet (:func:`~imdrive.analysis.nameplate_lee.lee_circuit`).

    Notes
    -----
    Equations in :mod:`imdrive.analysis.nameplate_lee`. The nameplate current is not an input
    of the method (``P``, ``eta`` and ``cos phi`` fix the input current); the estimate's
    ``rated_current_rms_A`` is still the plate's.
    """
    p = plate
    assumed = []
    if p.breakdown_torque_ratio is not None:
        assumed.append("breakdown torque ratio not used (method catalogue uses it)")
    I_lr = _locked_rotor_A(p, assumed)
    c = lee_circuit(
        p.power_W,
        p.voltage_V,
        p.slip,
        p.efficiency,
        p.power_factor,
        I_lr,
        leakage_split=p.leakage_split,
        core_loss_fraction=core_loss_fraction,
        mechanical_loss_fraction=mechanical_loss_fraction,
        stray_fraction=stray_loss_fraction,
    )
    machine = _machine(p, c.R1, c.R2, c.X1, c.X2, c.XM, description, assumed)
    ss = equivalent_circuit(machine, p.voltage_V, p.frequency_Hz, p.slip)
    residuals = {
        "rated_torque": float(ss.torque_Nm / p.torque_Nm - 1.0),
        "rated_current": float(ss.I1_rms_A / p.current_A - 1.0),
    }
    details = dict(
        RC_ohm=c.RC,
        locked_rotor_current_A=I_lr,
        iterations=c.iterations,
        **{f"{k}_W": v for k, v in c.losses_W.items()},
    )
    return NameplateFit(machine, residuals, tuple(assumed), method="lee", details=details)


def _locked_rotor_A(p: Nameplate, assumed: list) -> float:
    """The locked-rotor current, A rms: the catalogue's ``I_st / I_n``, else the code letter's,
    else :data:`DEFAULT_CODE_LETTER`'s (appended to ``assumed``)."""
    if p.starting_current_ratio is not None:
        return p.starting_current_ratio * p.current_A
    letter = p.code_letter
    if letter is None:
        letter = DEFAULT_CODE_LETTER
        assumed.append(f"NEMA code letter {DEFAULT_CODE_LETTER} (not given)")
    return locked_rotor_current_A(letter, p.power_W, p.voltage_V)


def estimate_circuit_catalogue(
    plate: Nameplate,
    description: str = "",
    core_loss_fraction: float | None = None,
    mechanical_loss_fraction: float | None = None,
    stray_loss_fraction: float | None = None,
) -> NameplateFit:
    """Estimate the plant's T-circuit from every figure of a catalogue.

    Parameters
    ----------
    plate : Nameplate
        The data: the rated point (power, voltage, frequency, poles, speed, power factor,
        efficiency), the design letter's leakage split, and the breakdown torque ratio
        (sets the leakage when given), else the starting current ratio, else the NEMA code
        letter (else :data:`DEFAULT_CODE_LETTER`, assumed and said so).
    description : str
        Text for the machine's ``description``.
    core_loss_fraction, mechanical_loss_fraction : float or None
        Core and friction-and-windage loss over the total loss ``P / eta - P``; None: 0.12
        and 0.14 (Lee et al.'s typical shares). Where the losses are known (a test report),
        give their shares.
    stray_loss_fraction : float or None
        Stray-load loss over ``P``; None: IEEE Std 112's assumed value by rating.

    Returns
    -------
    NameplateFit
        The machine; as residuals the circuit's relative error at the rated slip and
        voltage against the nameplate, ``rated_torque`` (the friction and stray losses the
        plant does not carry) and ``rated_current`` (the core-loss current it does not draw,
        and a nameplate current other than ``P / (sqrt 3 V eta cos phi)``), and when the
        breakdown torque set the leakage and a starting current is given, the circuit's
        ``starting_current`` against it (a deep-bar rotor's is larger than a single cage's);
        ``details`` holds the loss split, ``leakage_from`` and the circuit's breakdown torque
        and starting current.

    Raises
    ------
    ConfigError
        Data no circuit meets, naming the fields
        (:func:`~imdrive.analysis.nameplate_catalogue.catalogue_circuit`).

    Notes
    -----
    Equations and sources in :mod:`imdrive.analysis.nameplate_catalogue`.
    """
    p, assumed = plate, []
    given_bd = p.breakdown_torque_ratio is not None
    I_lr = None if given_bd else _locked_rotor_A(p, assumed)
    c = catalogue_circuit(
        p.power_W, p.voltage_V, p.frequency_Hz, p.poles, p.slip, p.efficiency,
        p.power_factor, p.breakdown_torque_ratio, I_lr, p.leakage_split,
        core_loss_fraction, mechanical_loss_fraction, stray_loss_fraction,
    )  # fmt: skip
    machine = _machine(p, c.R1, c.R2, c.X1, c.X2, c.XM, description, assumed)
    ss = equivalent_circuit(machine, p.voltage_V, p.frequency_Hz, p.slip)
    residuals = {
        "rated_torque": float(ss.torque_Nm / p.torque_Nm - 1.0),
        "rated_current": float(ss.I1_rms_A / p.current_A - 1.0),
    }
    if given_bd and p.starting_current_ratio is not None:
        I_st = p.starting_current_ratio * p.current_A
        residuals["starting_current"] = c.starting_current_A / I_st - 1.0
    details = dict(
        leakage_from=c.leakage_from,
        breakdown_torque_Nm=c.breakdown_torque_Nm,
        starting_current_A=c.starting_current_A,
        **{f"{k}_W": v for k, v in c.losses_W.items()},
    )
    return NameplateFit(machine, residuals, tuple(assumed), method="catalogue", details=details)
