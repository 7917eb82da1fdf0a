"""Nameplate and catalogue data -> T-equivalent circuit (an estimate, with its assumptions).

A motor's nameplate gives rated power ``P``, line voltage ``V``, frequency ``f``, poles,
speed ``n``, line current ``I``, power factor ``cos phi`` and efficiency ``eta``; a NEMA
nameplate adds the design letter (the leakage split) and the code letter (locked-rotor kVA
per hp); a catalogue adds the breakdown torque ratio ``T_bd / T_n`` and the starting current
ratio ``I_st / I_n``. Two methods estimate the single-cage T-circuit (``R1``, ``R2``, ``X1``,
``X2``, ``X_M``) that imdrive's plant model simulates:

``method="lee"`` (recommended: :func:`estimate_circuit_lee`)
    The published nameplate-only iterative method of K. Lee, S. Frank, P. K. Sen,
    L. Gentile Polese, M. Alahmad, C. Waters, "Estimation of induction motor equivalent
    circuit parameters from nameplate data", Proc. North American Power Symposium (NAPS),
    2012, doi:10.1109/NAPS.2012.6336384 (equations and citation check in
    :mod:`imdrive.analysis.nameplate_lee`). It splits the losses by typical fractions (core,
    friction and windage, stray load), so ``R1`` is a stator copper resistance, and takes the
    leakage from the locked-rotor current (code letter, or a catalogue's ``I_st / I_n``). Its
    core-loss resistance is dropped (the plant has no iron-loss branch), and the plant carries
    no friction or stray loss: loaded to rated torque, the plant turns a little faster and
    draws a little less current than the nameplate says, by the fractions of loss it does not
    carry (reported as ``rated_torque`` and ``rated_current`` residuals). On the library's
    machines, from the nameplate and its code letter alone, it reproduces the published
    circuits' breakdown torque within the bound docs/nameplate.md states
    (:mod:`imdrive.studies.nameplate_check`).

``method="fit"`` (:func:`estimate_circuit`'s default, kept for existing uses)
    ``R1`` from the rated point's power balance, then a least-squares fit of ``R2``,
    ``X1 + X2`` and ``X_M`` to the rated point's impedance and the breakdown torque (equations
    below): the formulation of the *manufacturer-data* methods, which fit the circuit to a
    catalogue's rated point and torque figures (J. Pedra, F. Córcoles, "Estimation of induction
    motor double-cage model parameters from manufacturer data", IEEE Trans. Energy Conversion
    19(2), 2004; M. H. Haque, "Determination of NEMA design induction motor parameters from
    manufacturer data", IEEE Trans. Energy Conversion 23(4), 2008; authors, titles and
    journals as cited in the literature, the papers' equations not re-checked here: the
    equations and the lumping of every loss into ``R1`` are this module's). It meets a given
    breakdown torque exactly; without one (nor a starting current) it assumes
    :data:`DEFAULT_BREAKDOWN_RATIO` and says so, which on the library's machines puts the
    breakdown torque up to 50 % off.

Equations of ``method="fit"`` (per phase, star equivalent, rms; ``s_n = 1 - n / n_sync``)::

    Z_n   = V_ph / I_n (cos phi + j sin phi)                 rated-point input impedance
    P_in  = 3 V_ph I_n cos phi,  P_ag = P / (1 - s_n)        (T_n = P / w_m, P_ag = T_n w_s)
    R1    = (P_in - P_ag) / (3 I_n^2)                        every loss but the rotor's
    Z(s)  = R1 + j X1 + (j X_M || (R2 / s + j X2)) = Z_n      at s = s_n     (2 equations)
    T_bd(R1, R2, X1, X2, X_M) = (T_bd / T_n) T_n              Thevenin closed form (1 equation)
    |Z(1)| = V_ph / I_st                                      if the starting current is given

with ``X1 = k (X1 + X2)``. The unknowns ``R2``, ``X1 + X2``, ``X_M`` (and ``k`` when the
starting current is also given) are found by least squares on the logarithms (exact when the
data are consistent: the residuals are reported).

Assumptions of ``method="fit"`` (the circuit is imdrive's plant model: no iron-loss branch,
no saturation, no deep-bar or double-cage effect):

* every loss other than the rotor copper loss (stator copper, iron, friction and windage,
  stray load) is lumped into ``R1``, so that the circuit's input power at the rated point is
  the electrical ``3 V_ph I_n cos phi``; ``R1`` is then larger than a measured stator
  resistance (by the iron, mechanical and stray losses over ``3 I^2``). The efficiency this
  implies, ``P / (sqrt 3 V I cos phi)``, is the nameplate's when the nameplate is
  consistent; the difference (rounding on a real plate) is reported as the ``efficiency``
  residual, and rated torque, current and power factor are met exactly whatever it is;
* the rotor copper loss is ``s P_ag`` (no mechanical loss between air gap and shaft);
* ``X1 / (X1 + X2) = k``: 0.5 for NEMA design A and D and wound rotors, 0.4 for design B,
  0.3 for design C (IEEE Std 112); the default 0.5;
* a single-cage circuit cannot reproduce both the rated point and the starting point of a
  deep-bar rotor: when both the breakdown torque and the starting current are given the fit
  frees ``k`` (kept within 0.05-0.95), and a residual remains if the data need a double
  cage;
* without a breakdown torque ratio (nor a starting current) the ratio is assumed
  (:data:`DEFAULT_BREAKDOWN_RATIO`), and the result says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from imdrive.analysis.circuit import equivalent_circuit
from imdrive.analysis.nameplate_lee import (
    CORE_LOSS_FRACTION,
    MECHANICAL_LOSS_FRACTION,
    NEMA_CODE_LETTERS,
    lee_circuit,
    locked_rotor_current_A,
)
from imdrive.config.machine import MachineParams
from imdrive.config.validation import FLOAT_MAX_MAGNITUDE, FLOAT_MIN_MAGNITUDE
from imdrive.errors import ConfigError, check_argument

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
    "estimate_circuit_lee",
]

#: The estimation methods of :func:`estimate_circuit` (module docstring).
METHODS = ("lee", "fit")

#: NEMA code letter assumed by ``method="lee"`` when neither it nor the starting current is
#: given: G (5.6-6.3 kVA/hp, a locked-rotor current of about 6 times rated on a typical
#: design B machine). An assumption, reported as such.
DEFAULT_CODE_LETTER = "G"

#: Breakdown torque over rated torque assumed when neither it nor the starting current is given
#: (a typical NEMA design B / IEC design N value; catalogues print the machine's own).
DEFAULT_BREAKDOWN_RATIO = 2.5

#: X1 / (X1 + X2) by NEMA design letter (IEEE Std 112).
LEAKAGE_SPLIT = {"A": 0.5, "B": 0.4, "C": 0.3, "D": 0.5, "wound": 0.5}

#: An inertia constant ``H = J w_m^2 / (2 P)``, s, for a J the data do not give.
DEFAULT_INERTIA_CONSTANT_S = 0.5


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
        Rotor inertia, kg m^2; ``None``: from an inertia constant of
        :data:`DEFAULT_INERTIA_CONSTANT_S`.
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
        for name, hi in (("breakdown_torque_ratio", 20.0), ("starting_current_ratio", 50.0)):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, int | float) and 1 < v <= hi):
                raise ConfigError(name, f"must be > 1 and <= {hi:g} (finite), got {v!r}")
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


def _impedance(R1, R2, X1, X2, XM, s):
    Z2 = R2 / s + 1j * X2
    return R1 + 1j * X1 + 1j * XM * Z2 / (Z2 + 1j * XM)


def _breakdown_torque(R1, X1, X2, XM, V_ph, w_s):
    """Maximum torque of the circuit (Thevenin form, rms phase voltage), N m."""
    den = R1 + 1j * (X1 + XM)
    V_th = V_ph * 1j * XM / den
    Z_th = 1j * XM * (R1 + 1j * X1) / den
    root = math.hypot(Z_th.real, Z_th.imag + X2)
    return 3.0 * abs(V_th) ** 2 / (2.0 * w_s * (Z_th.real + root))


def estimate_circuit(
    plate: Nameplate, description: str = "", method: str = "fit", **options
) -> NameplateFit:
    """Estimate the T-equivalent circuit from nameplate and catalogue data.

    Parameters
    ----------
    plate : Nameplate
        The data.
    description : str
        Text for the machine's ``description``.
    method : {"fit", "lee"}
        ``"fit"``: the least-squares fit (module docstring; the default, as before);
        ``"lee"``: the published nameplate-only method, :func:`estimate_circuit_lee`
        (recommended).
    **options
        ``method="lee"``: the loss fractions of :func:`estimate_circuit_lee`.

    Returns
    -------
    NameplateFit
        The machine (validated :class:`~imdrive.config.machine.MachineParams`), the fit's
        relative residuals and the assumptions made.

    Raises
    ------
    ConfigError
        Data no single-cage circuit can meet (naming the quantity).

    Notes
    -----
    The methods and their assumptions are in the module docstring.
    """
    try:
        return _estimate_circuit(plate, description, method, **options)
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
    if method == "lee":
        allowed = ("core_loss_fraction", "mechanical_loss_fraction", "stray_loss_fraction")
        extra = sorted(set(options) - set(allowed))
        if extra:
            raise ConfigError(extra[0], f"not an option of lee (it takes {', '.join(allowed)})")
        return estimate_circuit_lee(plate, description, **options)
    if method != "fit":
        raise ConfigError("method", f"must be one of {', '.join(METHODS)}, got {method!r}")
    if options:
        raise ConfigError("method", f"fit takes no options, got {', '.join(options)}")
    p = plate
    V_ph = p.voltage_V / math.sqrt(3.0)
    w_e = 2.0 * math.pi * p.frequency_Hz
    w_s = w_e / (p.poles / 2)  # synchronous mechanical speed, rad/s
    s_n = p.slip
    T_n = p.torque_Nm
    sin_phi = math.sqrt(1.0 - p.power_factor**2)
    Z_abs = V_ph / p.current_A
    Z_n = Z_abs * complex(p.power_factor, sin_phi)
    P_in = 3.0 * V_ph * p.current_A * p.power_factor
    P_ag = T_n * w_s
    R1 = (P_in - P_ag) / (3.0 * p.current_A**2)
    if not R1 > 0:
        raise ConfigError(
            "power_factor",
            f"sqrt(3) V I cos phi = {P_in:.5g} W is not above the air-gap power P / (1 - s) = "
            f"{P_ag:.5g} W (current or power factor too low for the power)",
        )

    assumed = []
    ratio = p.breakdown_torque_ratio
    if ratio is None and p.starting_current_ratio is None:
        ratio = DEFAULT_BREAKDOWN_RATIO
        assumed.append(f"breakdown torque ratio {DEFAULT_BREAKDOWN_RATIO:g} (not given)")
    free_split = ratio is not None and p.starting_current_ratio is not None

    def unpack(x):
        R2, Xl, XM = np.exp(x[:3])
        k = p.leakage_split
        if free_split:
            k = 0.05 + 0.9 / (1.0 + math.exp(-x[3]))
        return R2, k * Xl, (1.0 - k) * Xl, XM

    def residuals(x):
        R2, X1, X2, XM = unpack(x)
        Z = _impedance(R1, R2, X1, X2, XM, s_n)
        out = [(Z.real - Z_n.real) / Z_abs, (Z.imag - Z_n.imag) / Z_abs]
        if ratio is not None:
            out.append(_breakdown_torque(R1, X1, X2, XM, V_ph, w_s) / (ratio * T_n) - 1.0)
        if p.starting_current_ratio is not None:
            I_st = V_ph / abs(_impedance(R1, R2, X1, X2, XM, 1.0))
            out.append(I_st / (p.starting_current_ratio * p.current_A) - 1.0)
        return np.array(out)

    # start: rotor branch ~ R2/s resistive, magnetising current ~ 0.9 of the reactive current
    x0 = [
        math.log(s_n * (Z_n.real - R1)),
        math.log(0.15 * Z_abs),
        math.log(V_ph / (0.9 * p.current_A * max(sin_phi, 0.1))),
    ]
    if free_split:
        x0.append(math.log((p.leakage_split - 0.05) / (0.95 - p.leakage_split)))
    best = None
    for scale in (0.15, 0.05, 0.4):  # a few starts for the leakage: the fit is not convex
        x0[1] = math.log(scale * Z_abs)
        sol = least_squares(residuals, x0, method="lm" if not free_split else "trf", xtol=1e-15)
        if best is None or sol.cost < best.cost:
            best = sol
    R2, X1, X2, XM = unpack(best.x)
    r = residuals(best.x)
    names = ["rated_R", "rated_X"]
    if ratio is not None:
        names.append("breakdown_torque")
    if p.starting_current_ratio is not None:
        names.append("starting_current")
    fit = dict(zip(names, (float(v) for v in r), strict=True))
    fit["efficiency"] = p.power_W / P_in / p.efficiency - 1.0  # implied over given

    machine = _machine(p, R1, R2, X1, X2, XM, description, assumed)
    return NameplateFit(machine=machine, residuals=fit, assumed=tuple(assumed))


def _machine(p: Nameplate, R1, R2, X1, X2, XM, description: str, assumed: list) -> MachineParams:
    """The MachineParams of a circuit (ohm at the rated frequency) and its nameplate; J from
    the plate or an inertia constant (appended to ``assumed``)."""
    w_e = 2.0 * math.pi * p.frequency_Hz
    J = p.J_kgm2
    if J is None:
        w_m = p.speed_rpm * math.pi / 30.0
        J = 2.0 * DEFAULT_INERTIA_CONSTANT_S * p.power_W / w_m**2
        assumed.append(f"J from an inertia constant H = {DEFAULT_INERTIA_CONSTANT_S:g} s")
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
        assumed.append("breakdown torque ratio not used (method fit uses it)")
    if p.starting_current_ratio is not None:
        I_lr = p.starting_current_ratio * p.current_A
    else:
        letter = p.code_letter
        if letter is None:
            letter = DEFAULT_CODE_LETTER
            assumed.append(f"NEMA code letter {DEFAULT_CODE_LETTER} (not given)")
        I_lr = locked_rotor_current_A(letter, p.power_W, p.voltage_V)
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
