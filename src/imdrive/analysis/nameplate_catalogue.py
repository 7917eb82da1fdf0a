"""The catalogue method: one circuit from every figure a catalogue gives (pure functions).

Data: rated power ``P``, line voltage ``V``, frequency, poles, slip ``s``, efficiency
``eta``, power factor ``cos phi``, and, when given, the breakdown torque ratio ``T_bd / T_n``
and the locked-rotor (starting) current ``I_st``. The plant's circuit is the single-cage
T-circuit ``R1 + j X1``, ``j X_M``, ``R2 / s + j X2`` with no iron-loss branch, no friction and
no stray-load loss (the equivalent circuit of IEEE Std 112 and IEC 60034-28 less its iron-loss
resistance). Per phase, star equivalent, rms (``V_ph = V / sqrt 3``).

1. **Losses** (the split of K. Lee, S. Frank, P. K. Sen et al., NAPS 2012,
   :mod:`imdrive.analysis.nameplate_lee`, whose defaults are typical shares)::

       P_in = P / eta,  P_core = f_core (P_in - P),  P_mech = f_mech (P_in - P),
       P_stray = f_stray P,  P_ag = (P + P_mech + P_stray) / (1 - s),
       P_scl = P_in - P_ag - P_core                             stator copper loss

2. **R1 is the stator's**: ``R1 = P_scl / (3 I^2)`` with the input current
   ``I = P_in / (sqrt 3 V cos phi)``; no other loss is put into it.

3. **The rated point**, for a given total leakage ``X_s = X1 + X2`` (``X1 = k X_s``, ``k`` the
   design letter's split of IEEE Std 112): the plant draws at the rated slip the nameplate's
   reactive power and its active power less the core loss it does not carry::

       I1 = (P_in - P_core - j P_in tan phi) / (3 V_ph)
       E  = V_ph - (R1 + j X1) I1,   Y = I1 / E = 1 / (j X_M) + 1 / (R2 / s + j X2)

   ``Re Y`` gives ``R2`` (the larger root, the low-slip branch of the torque curve) and
   ``Im Y`` then ``X_M``, in closed form: the circuit meets ``I1`` exactly, and its air-gap
   power is the motor's ``P_ag`` (to the stator copper loss of the core-loss current, below
   0.1 % of ``P_ag``).

4. **The leakage** ``X_s``, one equation solved by Brent's method over the ``X_s`` the rated
   point admits (the largest leaves ``X_M`` infinite):

   * from the breakdown torque when the catalogue gives it, the exact Thevenin form of the
     circuit's maximum torque (A. E. Fitzgerald, C. Kingsley, S. D. Umans, *Electric
     Machinery*, 6th ed., McGraw-Hill, 2003, ch. 6)::

         V_th = V_ph j X_M / (R1 + j (X1 + X_M)),  Z_th = j X_M (R1 + j X1) / (R1 + j (X1 + X_M))
         T_bd = 3 |V_th|^2 / (2 w_s (Re Z_th + |Re Z_th + j (Im Z_th + X2)|)) = (T_bd / T_n) T_n

     With ``R1 = 0`` and ``X_M`` infinite this is the classical ``T_bd = 3 V_ph^2 / (2 w_s
     X_s)`` behind Kloss's relation ``T / T_bd = 2 / (s / s_bd + s_bd / s)``: the breakdown
     torque measures the leakage at running slips. A cage rotor's starting current does not:
     at standstill the rotor current crowds into the top of deep or double-cage bars, whose
     leakage is then smaller (and resistance larger) than at the rated slip, so a leakage
     taken from the starting current is too small and the breakdown torque too large (the
     22 kW catalogue motor of issue 39: 3.74 instead of 2.8 times rated torque);
   * otherwise from the locked-rotor current: ``|I1(s = 1)| = I_st`` of the whole circuit
     (magnetising branch included), ``I_st`` from the catalogue's ratio or the NEMA code
     letter (:func:`imdrive.analysis.nameplate_lee.locked_rotor_current_A`).

The breakdown torque a catalogue prints is a shaft torque; the plant has no friction, so its
electromagnetic breakdown torque is set to it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from scipy.optimize import brentq

from imdrive.analysis.nameplate_lee import loss_split
from imdrive.errors import ConfigError

__all__ = ["CatalogueCircuit", "catalogue_circuit", "breakdown_torque_Nm", "starting_current_A"]

#: Relative tolerance of the leakage solve.
_XTOL = 1e-13


@dataclass(frozen=True)
class CatalogueCircuit:
    """The circuit of :func:`catalogue_circuit` (per phase, star equivalent, ohm at rated
    frequency).

    Attributes
    ----------
    R1, R2, X1, X2, XM : float
        Stator and rotor resistance, stator and rotor leakage and magnetising reactance, ohm.
    leakage_from : str
        ``"breakdown torque"`` or ``"starting current"``: what set ``X1 + X2``.
    breakdown_torque_Nm, starting_current_A : float
        The circuit's breakdown torque, N m, and locked-rotor current, A rms, at rated voltage.
    losses_W : dict of str to float
        ``P_in``, ``P_core``, ``P_mech``, ``P_stray``, ``P_scl``, ``P_rcl``, ``P_ag``, W
        (:func:`~imdrive.analysis.nameplate_lee.loss_split`).
    """

    R1: float
    R2: float
    X1: float
    X2: float
    XM: float
    leakage_from: str
    breakdown_torque_Nm: float
    starting_current_A: float
    losses_W: dict = field(default_factory=dict)


def breakdown_torque_Nm(R1, X1, X2, XM, V_ph, w_s) -> float:
    """Maximum motoring torque of the circuit, N m (module docstring, step 4; rms ``V_ph``,
    synchronous mechanical speed ``w_s`` in rad/s)."""
    den = R1 + 1j * (X1 + XM)
    V_th = V_ph * 1j * XM / den
    Z_th = 1j * XM * (R1 + 1j * X1) / den
    root = math.hypot(Z_th.real, Z_th.imag + X2)
    return 3.0 * abs(V_th) ** 2 / (2.0 * w_s * (Z_th.real + root))


def starting_current_A(R1, R2, X1, X2, XM, V_ph) -> float:
    """Locked-rotor current ``|V_ph / Z(s = 1)|`` of the circuit, A rms."""
    Z2 = R2 + 1j * X2
    return V_ph / abs(R1 + 1j * X1 + 1j * XM * Z2 / (Z2 + 1j * XM))


def _rated_circuit(X_s, k, V, I1, R1, s):
    """``(R2, XM)`` meeting the rated point for the leakage ``X_s`` (step 3), or None where the
    rated point admits no such circuit (the leakage takes more reactive power than there is,
    or cannot pass the air-gap power)."""
    X1, X2 = k * X_s, (1.0 - k) * X_s
    E = V - (R1 + 1j * X1) * I1
    Y = I1 / E
    g = Y.real  # = x / (x^2 + X2^2), x = R2 / s
    if not g > 0:
        return None
    disc = 1.0 - 4.0 * g * g * X2 * X2
    if disc < 0:
        return None
    x = (1.0 + math.sqrt(disc)) / (2.0 * g)
    b_m = -Y.imag - X2 / (x * x + X2 * X2)  # 1 / X_M
    if not b_m > 0:
        return None
    return x * s, 1.0 / b_m


def catalogue_circuit(
    power_W: float,
    voltage_V: float,
    frequency_Hz: float,
    poles: int,
    slip: float,
    efficiency: float,
    power_factor: float,
    breakdown_torque_ratio: float | None = None,
    locked_rotor_A: float | None = None,
    leakage_split: float = 0.5,
    core_loss_fraction: float | None = None,
    mechanical_loss_fraction: float | None = None,
    stray_fraction: float | None = None,
) -> CatalogueCircuit:
    """The plant's T-circuit from catalogue data (module docstring).

    Parameters
    ----------
    power_W, voltage_V, frequency_Hz : float
        Rated shaft power, W, line voltage, V rms, frequency, Hz.
    poles : int
        Number of poles.
    slip, efficiency, power_factor : float
        At rated load, dimensionless.
    breakdown_torque_ratio : float or None
        ``T_bd / T_n``; sets the leakage when given.
    locked_rotor_A : float or None
        Locked-rotor current at rated voltage, A rms; sets the leakage when no breakdown
        torque is given. One of the two is needed.
    leakage_split : float
        ``X1 / (X1 + X2)``.
    core_loss_fraction, mechanical_loss_fraction, stray_fraction : float or None
        The loss split (:func:`~imdrive.analysis.nameplate_lee.loss_split`; None: its
        defaults).

    Returns
    -------
    CatalogueCircuit

    Raises
    ------
    ConfigError
        Data no circuit meets, naming the fields: the losses leave no stator copper loss
        (``efficiency``); the power factor leaves the leakage no room
        (``power_factor, efficiency``); the breakdown torque or starting current is out of the
        range the rated point admits (``breakdown_torque_ratio, power_factor`` or
        ``starting_current, power_factor``, with the range).
    """
    if breakdown_torque_ratio is None and locked_rotor_A is None:
        raise ConfigError("breakdown_torque_ratio", "a breakdown torque or starting current")
    L = loss_split(power_W, slip, efficiency, core_loss_fraction, mechanical_loss_fraction,
                   stray_fraction)  # fmt: skip
    V = voltage_V / math.sqrt(3.0)
    w_s = 4.0 * math.pi * frequency_Hz / poles
    tan_phi = math.sqrt(1.0 - power_factor**2) / power_factor
    I_in = L["P_in"] / (3.0 * V * power_factor)
    R1 = L["P_scl"] / (3.0 * I_in**2)
    I1 = complex(L["P_in"] - L["P_core"], -L["P_in"] * tan_phi) / (3.0 * V)
    k = leakage_split

    def circuit(X_s):
        return _rated_circuit(X_s, k, V, I1, R1, slip)

    Z_n = V / abs(I1)
    lo = 1e-6 * Z_n
    if circuit(lo) is None:
        raise ConfigError(
            "power_factor, efficiency",
            f"no circuit draws the rated current at power factor {power_factor:g} with the "
            "air-gap power the efficiency leaves (check both)",
        )
    hi = Z_n  # the largest admissible leakage, by bisection (admissibility is monotone)
    if circuit(hi) is None:
        a, b = lo, hi
        for _ in range(200):
            mid = math.sqrt(a * b)
            a, b = (mid, b) if circuit(mid) is not None else (a, mid)
            if b / a - 1.0 < 1e-12:
                break
        hi = a

    def properties(X_s):
        R2, XM = circuit(X_s)
        X1, X2 = k * X_s, (1.0 - k) * X_s
        return (R2, X1, X2, XM, breakdown_torque_Nm(R1, X1, X2, XM, V, w_s),
                starting_current_A(R1, R2, X1, X2, XM, V))  # fmt: skip

    T_n = power_W / (w_s * (1.0 - slip))
    if breakdown_torque_ratio is not None:
        target, index, source = breakdown_torque_ratio * T_n, 4, "breakdown torque"
        name, scale, unit = "breakdown_torque_ratio", 1.0 / T_n, " x rated torque"
    else:
        target, index, source = locked_rotor_A, 5, "starting current"
        name, scale, unit = "starting_current", 1.0, " A"
    at_hi, at_lo = properties(hi)[index], properties(lo)[index]
    if not at_hi <= target <= at_lo:
        raise ConfigError(
            f"{name}, power_factor",
            f"{source} {target * scale:.4g}{unit} is outside the {at_hi * scale:.4g}-"
            f"{at_lo * scale:.4g}{unit} that a single-cage circuit with this rated point "
            f"(slip {100 * slip:.3g} %, power factor {power_factor:g}, efficiency "
            f"{efficiency:g}) can have: check them together",
        )
    X_s = brentq(lambda x: properties(x)[index] / target - 1.0, lo, hi, xtol=_XTOL * lo,
                 rtol=1e-14, maxiter=500)  # fmt: skip
    R2, X1, X2, XM, T_bd, I_st = properties(X_s)
    return CatalogueCircuit(R1, R2, X1, X2, XM, source, T_bd, I_st, losses_W=L)
