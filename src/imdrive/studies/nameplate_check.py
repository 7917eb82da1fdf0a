"""Nameplate -> circuit, checked on the library's published machines.

For each machine of ``config/data/machines.toml`` the nameplate its published circuit has at
its rated torque (:func:`library_nameplate`: power ``T_n w_m``, that speed, current, power
factor and efficiency, and the NEMA code letter of its locked-rotor kVA per hp) is given to
:func:`imdrive.analysis.nameplate.estimate_circuit`; the estimated circuit is then loaded to
the rated torque at rated voltage and frequency (:func:`imdrive.config.rated.rated_point`,
the phasor circuit of :mod:`imdrive.analysis.circuit`) and compared with the published one.
Four data sets (:data:`CASES`):

* ``lee``, nameplate: the published nameplate-only method with the machine's code letter;
* ``lee``, ``I_st``: the same with the catalogue's starting current ratio instead;
* ``fit``, nameplate: the least-squares fit, whose breakdown ratio is then assumed (2.5);
* ``fit``, ``I_st``: the fit to the rated point and the starting current.

The library's circuits carry copper losses only (their efficiency is the circuit's), so the
Lee method is given zero core, mechanical and stray loss fractions here: its default split
(a real motor's) leaves these circuits no stator copper loss and is refused
(:func:`imdrive.analysis.nameplate_lee.lee_circuit`).
"""

from __future__ import annotations

import math
import warnings

import pandas as pd

from imdrive.analysis.circuit import equivalent_circuit
from imdrive.analysis.nameplate import Nameplate, estimate_circuit
from imdrive.analysis.nameplate_lee import code_letter_of
from imdrive.config.machine import machine_preset, machine_presets, rated_point
from imdrive.errors import ConfigWarning

#: (method, data) pairs of the check: ``nameplate`` = the nameplate only (with its NEMA code
#: letter), ``I_st`` = with the catalogue's starting current ratio.
CASES = (("lee", "nameplate"), ("lee", "I_st"), ("fit", "nameplate"), ("fit", "I_st"))

#: Largest breakdown-torque error, %, a case may show on any library machine (the tests' bound;
#: the table shows the measured errors). The least-squares fit without a breakdown ratio has
#: no bound: it assumes the ratio.
BREAKDOWN_TOL_PCT = {("lee", "nameplate"): 6.0, ("lee", "I_st"): 3.0, ("fit", "I_st"): 0.1}

#: Largest relative error of the rated torque, speed and current (every case: both methods
#: meet the rated point the data give, to round-off).
RATED_TOL = 1e-6

#: The loss split the library's circuits have (copper losses only).
COPPER_ONLY = dict(core_loss_fraction=0.0, mechanical_loss_fraction=0.0, stray_loss_fraction=0.0)


def library_nameplate(machine, data: str = "nameplate") -> Nameplate:
    """The nameplate a circuit has at its rated torque (rated voltage and frequency).

    Parameters
    ----------
    machine : MachineParams
        The published machine.
    data : {"nameplate", "I_st"}
        ``nameplate``: with the NEMA code letter of the circuit's locked-rotor kVA per hp
        (:func:`~imdrive.analysis.nameplate_lee.code_letter_of`); ``I_st``: with its starting
        current ratio instead.

    Returns
    -------
    Nameplate
        Power ``T_n w_m`` (``T_n`` the rated torque, ``w_m`` the circuit's speed at it),
        that speed, and the circuit's current, power factor and efficiency there.
    """
    rp = rated_point(machine)
    V, f = machine.rated_voltage_V, machine.rated_frequency_Hz
    power = rp.torque_Nm * rp.circuit_speed_rpm * math.pi / 30.0
    I_st = float(equivalent_circuit(machine, V, f, 1.0).I1_rms_A)
    extra = {}
    if data == "I_st":
        extra["starting_current_ratio"] = I_st / rp.circuit_current_rms_A
    else:
        extra["code_letter"] = code_letter_of(math.sqrt(3.0) * V * I_st / 1e3 / (power / 746.0))
    return Nameplate(
        power_W=power,
        voltage_V=V,
        frequency_Hz=f,
        poles=2 * machine.pole_pairs,
        speed_rpm=rp.circuit_speed_rpm,
        current_A=rp.circuit_current_rms_A,
        power_factor=rp.circuit_power_factor,
        efficiency=rp.efficiency,
        J_kgm2=machine.J_kgm2,
        **extra,
    )


def check_machine(name: str, method: str, data: str) -> dict:
    """One row of the check: the estimate of machine ``name`` against its published circuit.

    Returns
    -------
    dict
        ``machine, method, data, code_letter``, the relative errors (%) of the estimate's
        torque at the rated speed (``torque_err_pct``), its current (``current_err_pct``) and
        the speed error (rpm, ``speed_err_rpm``; and in per-unit of the rated slip,
        ``speed_err_pu_slip``) loaded to the rated torque, and of its breakdown torque
        (``breakdown_err_pct``); the published breakdown ratio ``T_bd_ratio``.
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        warnings.simplefilter("ignore", DeprecationWarning)  # lee and fit, compared on purpose
        m = machine_preset(name)
        rp = rated_point(m)
        plate = library_nameplate(m, data)
        options = COPPER_ONLY if method == "lee" else {}
        est = estimate_circuit(plate, method=method, **options).machine
        re = rated_point(est)
    V, f = m.rated_voltage_V, m.rated_frequency_Hz
    T_at_rated_speed = float(equivalent_circuit(est, V, f, plate.slip).torque_Nm)
    slip_rpm = rp.synchronous_speed_rpm - rp.circuit_speed_rpm
    return dict(
        machine=name,
        method=method,
        data=data,
        code_letter=plate.code_letter or "",
        T_bd_ratio=rp.breakdown_torque_Nm / rp.torque_Nm,
        torque_err_pct=100.0 * (T_at_rated_speed / rp.torque_Nm - 1.0),
        speed_err_rpm=re.circuit_speed_rpm - rp.circuit_speed_rpm,
        speed_err_pu_slip=(re.circuit_speed_rpm - rp.circuit_speed_rpm) / slip_rpm,
        current_err_pct=100.0 * (re.circuit_current_rms_A / rp.circuit_current_rms_A - 1.0),
        breakdown_err_pct=100.0 * (re.breakdown_torque_Nm / rp.breakdown_torque_Nm - 1.0),
    )


def run(machines=None, cases=CASES) -> pd.DataFrame:
    """The check over the library (default) for each of ``cases``: one row per machine and
    case (:func:`check_machine`)."""
    return pd.DataFrame(
        [
            check_machine(name, method, data)
            for name in machines or machine_presets()
            for method, data in cases
        ]
    )


_LABELS = {
    ("lee", "nameplate"): "lee, nameplate",
    ("lee", "I_st"): "lee, I_st/I_n",
    ("fit", "nameplate"): "fit, nameplate (T_bd/T_n = 2.5 assumed)",
    ("fit", "I_st"): "fit, I_st/I_n",
}


def markdown(df: pd.DataFrame) -> list[str]:
    """The table of docs/machines.md: per machine, the breakdown torque error of each case, and
    the largest rated-point errors over the cases of each method.

    Parameters
    ----------
    df : pandas.DataFrame
        As :func:`run` returns it (or read back from its CSV).

    Returns
    -------
    list of str
        Markdown lines.
    """
    cases = list(dict.fromkeys(zip(df["method"], df["data"], strict=True)))
    head = ["machine", "code letter", "published T_bd/T_n"]
    head += [f"T_bd error, {_LABELS.get(c, ' '.join(c))}" for c in cases]
    head += ["rated torque, speed, current: largest relative error (speed: of the slip)"]
    lines = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for name, g in df.groupby("machine", sort=False):
        row = [f"`{name}`", g["code_letter"].dropna().iloc[0], f"{g['T_bd_ratio'].iloc[0]:.2f}"]
        for method, data in cases:
            r = g[(g["method"] == method) & (g["data"] == data)].iloc[0]
            row.append(f"{round(r['breakdown_err_pct'], 1) + 0.0:+.1f} %")  # no -0.0
        worst = max(
            g["torque_err_pct"].abs().max() / 100.0,
            g["speed_err_pu_slip"].abs().max(),
            g["current_err_pct"].abs().max() / 100.0,
        )
        row.append("< 1e-9" if worst < 1e-9 else f"{worst:.1e}")
        lines.append("| " + " | ".join(row) + " |")
    bounds = "; ".join(f"{_LABELS[c]}: {v:g} %" for c, v in BREAKDOWN_TOL_PCT.items())
    lines += [
        "",
        f"Bounds the tests hold on every machine: breakdown torque error {bounds}; rated "
        f"torque, speed (relative to the rated slip) and current {RATED_TOL:g} relative.",
    ]
    return lines
