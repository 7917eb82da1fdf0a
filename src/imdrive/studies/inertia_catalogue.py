"""Default rotor inertia against catalogue motors (the inertia table of docs/nameplate.md).

The catalogue motors are in ``imdrive/studies/data/catalogue_inertia.csv``: manufacturer,
model, rated power, poles, frequency, rated speed, the catalogue's rotor inertia ``J``, the
row's role and its source (document, page, edition or date where printed, address). Every
figure is the source's; none is typed from memory. ``role`` says how a row is used:

* ``fit``: the 17 motors of one manufacturer's catalogue (SOGA MT3 IE3, 0.75-22 kW, 2 and 4
  poles) that :func:`fit_power_law` fits the law to;
* ``check``: motors not used by the fit: Sgath and WAT (one each); the Motive Delphi
  catalogue (2, 4, 6 and 8 poles, 0.75-315 kW, every row from 0.75 kW except the 160M-6,
  whose printed 0.0081 kg m^2 is a fifth of the smaller 132MB-6's and a fourteenth of the
  160L-6's, a misprint); and the two library machines whose J is published with them and
  is not known to include a load (Krause et al.'s 500 hp and 2250 hp, from the presets of
  ``imdrive/config/data/machines.toml``). Krause's 3 hp and 50 hp machines are left out:
  their J (0.089 and 1.662 kg m^2) are 12 and 4 times the law's and 13 and 4 times a Motive
  rotor of the same power and poles, which reads as a load included, and the text read does
  not say; the Aalto 2.2 kW machine's J is motulator's total inertia of the test bench; the
  Geyer machine's J is assumed.

:func:`run` compares each catalogue ``J`` with the default of
:func:`imdrive.analysis.inertia.rotor_inertia_kgm2` (``J = k_J (T_n / 1 N m)^a_J``) and with
the former default ``J = 2 H P / w_m^2`` at ``H = 0.5 s``. :func:`markdown` sums the ratio
up by range: the fit's own motors, the other motors up to the fit's largest power (22 kW),
and the motors above it, where the law is an extrapolation of the fit (30 kW - 1.68 MW).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd

from imdrive.analysis.inertia import inertia_constant_s, rotor_inertia_kgm2

#: The catalogue motors (module docstring).
DATA = Path(__file__).resolve().parent / "data" / "catalogue_inertia.csv"

#: The goal of issue 39: the default within this factor of the catalogue's J ...
WITHIN = 1.5
#: ... for at least this many catalogue motors.
MIN_WITHIN = 10

#: The inertia constant of the former default (imdrive 0.1), s.
FORMER_H_S = 0.5


def catalogue() -> pd.DataFrame:
    """The catalogue motors (:data:`DATA`), one row each, in the file's units."""
    return pd.read_csv(DATA)


def rated_torque_Nm(power_kW, speed_rpm):
    """``T_n = P / w_m``, N m, of rated power ``power_kW`` (kW) and speed ``speed_rpm``."""
    return np.asarray(power_kW, dtype=float) * 1e3 / (np.asarray(speed_rpm) * math.pi / 30.0)


def fit_power_law(df: pd.DataFrame | None = None) -> tuple[float, float]:
    """The least-squares line ``log J = log k_J + a_J log(T_n / 1 N m)`` through the ``fit`` rows.

    Parameters
    ----------
    df : DataFrame or None
        Catalogue rows (:func:`catalogue`'s columns); None: :func:`catalogue`.

    Returns
    -------
    tuple of float
        ``(k_J, a_J)``: kg m^2 and dimensionless; the constants of
        :mod:`imdrive.analysis.inertia` are these, rounded.
    """
    df = catalogue() if df is None else df
    rows = df[df["role"] == "fit"]
    T = rated_torque_Nm(rows["power_kW"], rows["speed_rpm"])
    a, log_k = np.polyfit(np.log(T), np.log(rows["J_kgm2"].to_numpy(float)), 1)
    return float(math.exp(log_k)), float(a)


def run() -> pd.DataFrame:
    """Each catalogue motor's J against the default's and the former default's.

    Returns
    -------
    DataFrame
        One row per motor: ``manufacturer, model, role, power_kW, poles, speed_rpm,
        T_n_Nm, J_catalogue_kgm2, J_default_kgm2, ratio`` (default over catalogue,
        dimensionless), ``H_catalogue_s, H_default_s`` (s) and ``ratio_former`` (the former
        ``H = 0.5 s`` default over the catalogue's).
    """
    df = catalogue()
    rows = []
    for r in df.itertuples():
        P = r.power_kW * 1e3
        J_default = rotor_inertia_kgm2(P, r.speed_rpm)
        J_former = 2.0 * FORMER_H_S * P / (r.speed_rpm * math.pi / 30.0) ** 2
        rows.append(
            dict(
                manufacturer=r.manufacturer,
                model=r.model,
                role=r.role,
                power_kW=r.power_kW,
                poles=r.poles,
                speed_rpm=r.speed_rpm,
                T_n_Nm=float(rated_torque_Nm(r.power_kW, r.speed_rpm)),
                J_catalogue_kgm2=r.J_kgm2,
                J_default_kgm2=J_default,
                ratio=J_default / r.J_kgm2,
                H_catalogue_s=inertia_constant_s(r.J_kgm2, P, r.speed_rpm),
                H_default_s=inertia_constant_s(J_default, P, r.speed_rpm),
                ratio_former=J_former / r.J_kgm2,
            )
        )
    return pd.DataFrame(rows)


def within(ratio, factor: float = WITHIN):
    """Whether each default-over-catalogue ``ratio`` (dimensionless) is within ``factor``
    (dimensionless) either way."""
    ratio = np.asarray(ratio, dtype=float)
    return (ratio <= factor) & (ratio >= 1.0 / factor)


def _spread(ratio) -> float:
    """The worst factor either way, dimensionless (1.5 for a ratio of 1.5 or 1/1.5)."""
    r = np.asarray(ratio, dtype=float)
    return float(np.max(np.maximum(r, 1.0 / r)))


def markdown(df: pd.DataFrame) -> list[str]:
    """The inertia table of docs/nameplate.md (from :func:`run`'s rows, or its CSV read back)."""
    head = ["motor", "role", "P, poles, n", "T_n", "J catalogue", "J default (H)", "ratio"]
    head += ["former H = 0.5 s: ratio"]
    lines = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for _, r in df.iterrows():
        lines.append(
            f"| {r['manufacturer']} {r['model']} | {r['role']} | {r['power_kW']:g} kW, "
            f"{r['poles']:d}, {r['speed_rpm']:g} rpm | {r['T_n_Nm']:.3g} N m | "
            f"{r['J_catalogue_kgm2']:.3g} kg m² | {r['J_default_kgm2']:.3g} kg m² "
            f"({r['H_default_s']:.3g} s) | {r['ratio']:.3f} | {r['ratio_former']:.3g} |"
        )
    ok = within(df["ratio"])
    fit = (df["role"] == "fit").to_numpy()
    P_fit = float(df["power_kW"][fit].max())
    above = (df["power_kW"] > P_fit).to_numpy()
    others = ~fit & ~above

    def _range(mask) -> str:
        r = df["ratio"][mask]
        return (
            f"{int(ok[mask].sum())} of {int(mask.sum())}, worst factor {_spread(r):.3f}, "
            f"median ratio {float(np.median(r)):.3f}"
        )

    lines += [
        "",
        f"Default within a factor of {WITHIN:g} of the catalogue's J: {int(ok.sum())} of "
        f"{len(df)} motors. The fit's own ({df['power_kW'][fit].min():g}-{P_fit:g} kW): "
        f"{_range(fit)}; the other manufacturers' up to {P_fit:g} kW: {_range(others)}; above "
        f"{P_fit:g} kW, where the law is an extrapolation of the fit "
        f"({df['power_kW'][above].min():.4g}-{df['power_kW'][above].max():.4g} kW): "
        f"{_range(above)}. The former H = 0.5 s default: "
        f"{int(within(df['ratio_former']).sum())} of {len(df)} "
        f"({int(within(df['ratio_former'][above]).sum())} of {int(above.sum())} above "
        f"{P_fit:g} kW), worst factor {_spread(df['ratio_former']):.3g}.",
    ]
    return lines
