"""The nameplate-only iterative method of Lee, Frank, Sen et al. (pure functions).

K. Lee, S. Frank, P. K. Sen, L. Gentile Polese, M. Alahmad, C. Waters, "Estimation of
induction motor equivalent circuit parameters from nameplate data", Proc. 2012 North American
Power Symposium (NAPS), Urbana, IL, Sep. 2012, pp. 1-6, doi:10.1109/NAPS.2012.6336384.
(Authors, title and the method's four steps checked against the paper's text; venue, year,
pages and DOI checked against the reference its co-author S. Frank gives in his MATLAB
implementation ``fitInductionMotorParam``. The paper's own equations were not available here:
the equations below and the default loss split are those of that implementation, written
anew, no code of it reused.)

The method needs only what a NEMA nameplate prints: rated power ``P``, line voltage ``V``,
frequency, speed (slip ``s``), efficiency ``eta``, power factor ``cos phi``, NEMA design
letter (the leakage split ``k = X1 / (X1 + X2)``) and code letter (locked-rotor kVA per hp,
hence the locked-rotor current ``I_LR``). Its steps: the rated input, then the losses split by
typical fractions, then a set of power-balance equations for the circuit's elements, solved
by Gauss-Seidel iteration. Per phase, star equivalent, rms (``V_ph = V / sqrt 3``; powers
below are per phase, one third of the machine's)::

    P_in   = P / eta,  P_loss = P_in - P                             input, total loss
    P_core = f_core P_loss,  P_mech = f_mech P_loss,  P_stray = f_stray P
    P_conv = P + P_mech + P_stray                                     converted power
    P_ag   = P_conv / (1 - s)                                         air-gap power
    P_scl  = P_in - P_ag - P_core                                     stator copper loss
    Q_in   = P_in tan phi,  I1 = (P_in - j Q_in) / V_ph               stator current phasor
    R1     = P_scl / |I1|^2

and, from ``E = V_ph`` and ``X2 = 0``, repeated until no element changes (relative 1e-12)::

    R2   = s (|E|^2 + sqrt(|E|^4 - 4 P_ag^2 X2^2)) / (2 P_ag)   P_ag = |E|^2 Re 1/(R2/s + j X2)
    X_LR = sqrt((V_ph / I_LR)^2 - (R1 + R2)^2)       locked rotor, magnetising branch open
    X1   = k X_LR,  X2 = (1 - k) X_LR
    X_M  = |E|^2 / (Q_in - X1 |I1|^2 - X2 |I2|^2)    reactive power balance
    R_C  = |E|^2 / P_core                            core loss
    E    = V_ph - (R1 + j X1) I1,  I2 = E / (R2/s + j X2)

The stray-load loss is part of the rotor's load resistance ``R2 (1 - s) / s`` (the rotor
branch stays ``R2/s + j X2``).

Defaults of the loss split (the implementation's; typical values, not this machine's):
``f_core = 0.12`` and ``f_mech = 0.14`` of the total loss; ``f_stray`` of the rated output by
rating, the assumed stray-load loss of IEEE Std 112 (1.8 % up to 90 kW, 1.5 % to 375 kW,
1.2 % to 1850 kW, 0.9 % above). NEMA code letters (locked-rotor kVA per hp, NEMA MG 1) are
read at the middle of their band (A at its top, 3.15; V at its bottom, 22.4), with 1 hp =
0.746 kW. The split ``k``: 0.5 for NEMA designs A, D and wound rotors, 0.4 for B, 0.3 for C
(IEEE Std 112).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from imdrive.errors import ConfigError

__all__ = [
    "CORE_LOSS_FRACTION",
    "MECHANICAL_LOSS_FRACTION",
    "NEMA_CODE_LETTERS",
    "LeeCircuit",
    "code_letter_kva_per_hp",
    "code_letter_of",
    "lee_circuit",
    "locked_rotor_current_A",
    "loss_split",
    "stray_loss_fraction",
]

#: Core loss over total loss (the method's default; a typical share, not this machine's).
CORE_LOSS_FRACTION = 0.12
#: Friction and windage loss over total loss (the method's default).
MECHANICAL_LOSS_FRACTION = 0.14

#: NEMA MG 1 code letters: locked-rotor kVA per hp, (from, to).
NEMA_CODE_LETTERS = {
    "A": (0.0, 3.15),
    "B": (3.15, 3.55),
    "C": (3.55, 4.0),
    "D": (4.0, 4.5),
    "E": (4.5, 5.0),
    "F": (5.0, 5.6),
    "G": (5.6, 6.3),
    "H": (6.3, 7.1),
    "J": (7.1, 8.0),
    "K": (8.0, 9.0),
    "L": (9.0, 10.0),
    "M": (10.0, 11.2),
    "N": (11.2, 12.5),
    "P": (12.5, 14.0),
    "R": (14.0, 16.0),
    "S": (16.0, 18.0),
    "T": (18.0, 20.0),
    "U": (20.0, 22.4),
    "V": (22.4, math.inf),
}

_W_PER_HP = 746.0  # NEMA's kVA/hp with 1 hp = 0.746 kW


def stray_loss_fraction(power_W: float) -> float:
    """Assumed stray-load loss over rated output by rating (IEEE Std 112), dimensionless.

    Parameters
    ----------
    power_W : float
        Rated output, W.

    Returns
    -------
    float
        0.018 up to 90 kW, 0.015 up to 375 kW, 0.012 up to 1850 kW, 0.009 above.
    """
    kW = power_W / 1e3
    return 0.018 if kW <= 90 else 0.015 if kW <= 375 else 0.012 if kW <= 1850 else 0.009


def code_letter_kva_per_hp(letter: str) -> float:
    """The locked-rotor kVA per hp read for a NEMA code letter: the middle of its band (A: its
    top 3.15; V: its bottom 22.4).

    Parameters
    ----------
    letter : str
        A key of :data:`NEMA_CODE_LETTERS`.

    Returns
    -------
    float
        kVA per hp.
    """
    if letter not in NEMA_CODE_LETTERS:
        raise ConfigError("code_letter", f"must be a NEMA code letter A-V, got {letter!r}")
    lo, hi = NEMA_CODE_LETTERS[letter]
    return hi if letter == "A" else lo if letter == "V" else 0.5 * (lo + hi)


def code_letter_of(kva_per_hp: float) -> str:
    """The NEMA code letter whose band holds ``kva_per_hp`` (locked-rotor kVA per hp)."""
    return next(k for k, (lo, hi) in NEMA_CODE_LETTERS.items() if lo <= kva_per_hp < hi)


def locked_rotor_current_A(letter: str, power_W: float, voltage_V: float) -> float:
    """Locked-rotor line current of a code letter, A rms: ``kVA/hp (P / 746 W) / (sqrt 3 V)``.

    Parameters
    ----------
    letter : str
        NEMA code letter.
    power_W, voltage_V : float
        Rated output, W, and line voltage, V rms.

    Returns
    -------
    float
        A rms.
    """
    kva = code_letter_kva_per_hp(letter) * power_W / _W_PER_HP
    return kva * 1e3 / (math.sqrt(3.0) * voltage_V)


@dataclass(frozen=True)
class LeeCircuit:
    """The circuit of :func:`lee_circuit` (per phase, star equivalent, ohm at rated frequency).

    Attributes
    ----------
    R1, R2, X1, X2, XM : float
        Stator and rotor resistance, stator and rotor leakage and magnetising reactance, ohm.
    RC : float
        Core-loss resistance across the magnetising branch, ohm (``inf`` without core loss).
    iterations : int
        Gauss-Seidel sweeps to convergence.
    losses_W : dict of str to float
        The machine's (three-phase) ``P_in``, ``P_core``, ``P_mech``, ``P_stray``, ``P_scl``
        (stator copper), ``P_rcl`` (rotor copper) and ``P_ag`` (air gap), W.
    """

    R1: float
    R2: float
    X1: float
    X2: float
    XM: float
    RC: float
    iterations: int
    losses_W: dict = field(default_factory=dict)


def lee_circuit(
    power_W: float,
    voltage_V: float,
    slip: float,
    efficiency: float,
    power_factor: float,
    locked_rotor_current_A: float,
    leakage_split: float = 0.5,
    core_loss_fraction: float = CORE_LOSS_FRACTION,
    mechanical_loss_fraction: float = MECHANICAL_LOSS_FRACTION,
    stray_fraction: float | None = None,
    tol: float = 1e-12,
    max_iterations: int = 200,
) -> LeeCircuit:
    """The T-circuit with core-loss branch from nameplate data (Lee et al., NAPS 2012).

    Parameters
    ----------
    power_W : float
        Rated output, W.
    voltage_V : float
        Rated line voltage, V rms.
    slip : float
        Rated slip, dimensionless.
    efficiency, power_factor : float
        At rated load, dimensionless.
    locked_rotor_current_A : float
        Line current at standstill and rated voltage, A rms (from the code letter:
        :func:`locked_rotor_current_A`, or a catalogue's ``I_st / I_n``).
    leakage_split : float
        ``X1 / (X1 + X2)``, dimensionless.
    core_loss_fraction, mechanical_loss_fraction : float
        Core and friction-and-windage loss over the total loss ``P / eta - P``.
    stray_fraction : float or None
        Stray-load loss over ``P``; None: :func:`stray_loss_fraction`.
    tol : float
        Relative change of every element that ends the iteration.
    max_iterations : int
        Sweeps before giving up.

    Returns
    -------
    LeeCircuit
        The elements, the sweeps and the loss split.

    Raises
    ------
    ConfigError
        Data the method cannot meet, naming the quantity: the assumed losses leave no stator
        copper loss (``efficiency``), the locked-rotor current is too large for the
        resistances or too small for the air-gap power (``locked_rotor_current``), the
        leakage takes more reactive power than the machine draws (``power_factor``), or no
        convergence.

    Notes
    -----
    The equations are in the module docstring.
    """
    V = voltage_V / math.sqrt(3.0)
    f_stray = stray_loss_fraction(power_W) if stray_fraction is None else stray_fraction
    L = loss_split(power_W, slip, efficiency, core_loss_fraction, mechanical_loss_fraction, f_stray)
    tan_phi = math.sqrt(1.0 - power_factor**2) / power_factor
    I1 = complex(L["P_in"], -L["P_in"] * tan_phi) / (3.0 * V)  # per phase
    R1 = L["P_scl"] / 3.0 / abs(I1) ** 2
    E, R2, X1, X2, XM, sweeps = _sweeps(
        V,
        I1,
        R1,
        slip,
        L["P_ag"] / 3.0,
        locked_rotor_current_A,
        leakage_split,
        tol,
        max_iterations,
    )
    RC = abs(E) ** 2 / (L["P_core"] / 3.0) if L["P_core"] > 0 else math.inf
    return LeeCircuit(
        R1=R1,
        R2=R2,
        X1=X1,
        X2=X2,
        XM=XM,
        RC=RC,
        iterations=sweeps,
        losses_W=L,
    )


def loss_split(
    power_W: float,
    slip: float,
    efficiency: float,
    f_core: float | None = None,
    f_mech: float | None = None,
    f_stray: float | None = None,
) -> dict:
    """The machine's input, losses and air-gap power, W (module docstring's first block).

    Parameters
    ----------
    power_W : float
        Rated output, W.
    slip, efficiency : float
        At rated load, dimensionless.
    f_core, f_mech : float or None
        Core and friction-and-windage loss over the total loss ``P / eta - P``; None:
        :data:`CORE_LOSS_FRACTION`, :data:`MECHANICAL_LOSS_FRACTION`.
    f_stray : float or None
        Stray-load loss over ``P``; None: :func:`stray_loss_fraction`.

    Returns
    -------
    dict
        ``P_in``, ``P_core``, ``P_mech``, ``P_stray``, ``P_scl`` (stator copper), ``P_rcl``
        (rotor copper), ``P_ag`` (air gap), W.

    Raises
    ------
    ConfigError
        A fraction outside 0-1, or losses that leave no stator copper loss (``efficiency``).
    """
    f_core = CORE_LOSS_FRACTION if f_core is None else f_core
    f_mech = MECHANICAL_LOSS_FRACTION if f_mech is None else f_mech
    f_stray = stray_loss_fraction(power_W) if f_stray is None else f_stray
    for name, v in (
        ("core_loss_fraction", f_core),
        ("mechanical_loss_fraction", f_mech),
        ("stray_loss_fraction", f_stray),
    ):
        if not (math.isfinite(v) and 0.0 <= v < 1.0):
            raise ConfigError(name, f"must be within 0-1, got {v!r}")
    if not f_core + f_mech < 1.0:
        raise ConfigError("core_loss_fraction", "core + mechanical loss fractions must be < 1")
    P_in = power_W / efficiency
    P_loss = P_in - power_W
    P_core, P_mech, P_stray = f_core * P_loss, f_mech * P_loss, f_stray * power_W
    P_ag = (power_W + P_mech + P_stray) / (1.0 - slip)
    P_scl = P_in - P_ag - P_core
    if not P_scl > 0:
        raise ConfigError(
            "efficiency",
            f"the losses P/eta - P = {P_loss:.5g} W leave no stator copper loss once the "
            f"rotor's {slip * P_ag:.5g} W and the assumed core, mechanical and stray "
            f"{P_core + P_mech + P_stray:.5g} W are taken (lower the loss fractions)",
        )
    return dict(
        P_in=P_in,
        P_core=P_core,
        P_mech=P_mech,
        P_stray=P_stray,
        P_scl=P_scl,
        P_rcl=slip * P_ag,
        P_ag=P_ag,
    )


def _sweeps(V, I1, R1, slip, p_ag, I_lr, k, tol, max_iterations):
    """The Gauss-Seidel sweeps of the module docstring (per phase): ``E, R2, X1, X2, XM`` and
    the number of sweeps."""
    q_in = -(V * I1).imag  # reactive input per phase (V real, I1 lagging)
    Z_lr = V / I_lr
    E, I2_abs, X2 = complex(V, 0.0), I1.real, 0.0
    old, sweeps = None, 0
    while True:
        sweeps += 1
        if sweeps > max_iterations:
            raise ConfigError("nameplate", f"no convergence in {max_iterations} sweeps")
        disc = abs(E) ** 4 - 4.0 * p_ag**2 * X2**2
        if disc < 0:
            raise ConfigError(
                "locked_rotor_current",
                f"{I_lr:.5g} A is too small: its leakage reactance cannot carry the air-gap "
                "power at rated slip",
            )
        R2 = slip * (abs(E) ** 2 + math.sqrt(disc)) / (2.0 * p_ag)
        if not Z_lr > R1 + R2:
            raise ConfigError(
                "locked_rotor_current",
                f"{I_lr:.5g} A is too large: V / I_LR = {Z_lr:.4g} ohm is not above R1 + R2 = "
                f"{R1 + R2:.4g} ohm",
            )
        X_lr = math.sqrt(Z_lr**2 - (R1 + R2) ** 2)
        X1, X2 = k * X_lr, (1.0 - k) * X_lr
        q_m = q_in - X1 * abs(I1) ** 2 - X2 * I2_abs**2
        if not q_m > 0:
            raise ConfigError(
                "power_factor",
                "the leakage reactances take all the reactive power the power factor leaves "
                "(locked-rotor current too small, or power factor too high)",
            )
        XM = abs(E) ** 2 / q_m
        E = V - (R1 + 1j * X1) * I1
        I2_abs = abs(E / (R2 / slip + 1j * X2))
        new = (R2, X1, X2, XM)
        if old is not None and all(
            abs(a - b) <= tol * abs(a) for a, b in zip(new, old, strict=True)
        ):
            return E, R2, X1, X2, XM, sweeps
        old = new
