"""The least-squares ``fit`` method of :func:`imdrive.analysis.nameplate.estimate_circuit`
(deprecated for ``method="catalogue"``, :mod:`imdrive.analysis.nameplate_catalogue`, whose R1
is the stator's).

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

import numpy as np
from scipy.optimize import least_squares

from imdrive.errors import ConfigError

__all__ = ["DEFAULT_BREAKDOWN_RATIO", "fit_circuit"]

#: Breakdown torque over rated torque assumed when neither it nor the starting current is given
#: (a typical NEMA design B / IEC design N value; catalogues print the machine's own).
DEFAULT_BREAKDOWN_RATIO = 2.5


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


def fit_circuit(p) -> tuple[tuple, dict, list]:
    """The least-squares circuit of a nameplate (module docstring).

    Parameters
    ----------
    p : imdrive.analysis.nameplate.Nameplate
        The data.

    Returns
    -------
    circuit : tuple of float
        ``R1, R2, X1, X2, XM``, ohm at the rated frequency.
    residuals : dict of str to float
        Relative residuals of the fitted quantities and of the efficiency.
    assumed : list of str
        What was assumed for want of data.

    Raises
    ------
    ConfigError
        A current or power factor too low for the power (``power_factor``).
    """
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

    return (R1, R2, X1, X2, XM), fit, assumed
