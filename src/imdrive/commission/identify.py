"""The identification run: the four tests in order, what they found, and its files.

Order (each test uses what the earlier ones found): the standstill DC test (R1, the inverter's
error table; :mod:`~imdrive.commission.dc`), the rotating no-load test (L1(psi), the
magnetising curve; :mod:`~imdrive.commission.noload`), the standstill AC test (the leakage and
R2; :mod:`~imdrive.commission.ac`), the acceleration test (J;
:mod:`~imdrive.commission.inertia`). The plant's parameters are read only by :func:`truth`,
to report them beside the identified ones.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from imdrive.commission.ac import ac_test
from imdrive.commission.base import check_commissionable, guess_model, nameplate, switched_off
from imdrive.commission.dc import dc_test
from imdrive.commission.inertia import acceleration_test
from imdrive.commission.noload import noload_test
from imdrive.commission.rotor_time import rotor_time_test
from imdrive.config.scenario import SECTIONS, Scenario

#: The flux range over which the magnetising curve's accuracy is stated, per unit of rated.
CURVE_RANGE_PU = (0.3, 1.1)


@dataclass
class CommissioningResult:
    """What the identification run found.

    Attributes
    ----------
    identified : dict
        ``R1_ohm``, ``R2_ohm``, ``sigma_L1_H``, ``L1_H``, ``Ll_H``, ``M_H``, ``J_kgm2``,
        ``magnetising`` (``psi_Wb``, ``Lm_H``), ``inverter_error`` (``i_A``, ``u_V``),
        ``current_gain_b_per_a`` (the current sensors' relative gain).
    true : dict
        The plant's values of the same quantities (the simulator's; a real drive has none).
    relative_error : dict
        ``identified/true - 1`` of each scalar; ``Lm_H``: the largest over the curve's
        points within :data:`CURVE_RANGE_PU` of rated flux; ``u_err_V``: of the table's plateau
        (None for an inverter that loses nothing).
    durations_s : dict
        Simulated duration of each test.
    wall_s : float
        Wall time of the run.
    tests : dict
        Each test's result object (for the figures).
    switched_off : list of str
        What the input scenario has on that the tests ran without, one line each
        (:func:`~imdrive.commission.base.switched_off`).
    nameplate : dict
        Where the rated current, speed and torque the tests used came from.
    """

    identified: dict
    true: dict
    relative_error: dict
    durations_s: dict
    wall_s: float
    tests: dict = field(default_factory=dict)
    switched_off: list = field(default_factory=list)
    nameplate: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """The ``summary.json`` content."""
        return {
            "identified": self.identified,
            "true": self.true,
            "relative_error": self.relative_error,
            "durations_s": self.durations_s,
            "wall_s": self.wall_s,
            "switched_off": self.switched_off,
            "nameplate": self.nameplate,
        }


def identify(sc: Scenario) -> CommissioningResult:
    """Run the four tests on scenario ``sc`` and collect the identified model."""
    t_wall = time.perf_counter()
    check_commissionable(sc)
    npl = nameplate(sc)
    model = guess_model(npl)
    step = rotor_time_test(sc, npl, model)
    T2 = step.T2_s
    dc = dc_test(sc, npl, model, T2)
    table = (dc.i_A, dc.u_V)
    nl = noload_test(sc, npl, dc.R1_ohm, table, model, T2)
    Ll = model["Ll1_H"]
    for _ in range(2):  # the magnetising current depends (a little) on the leakage found
        _, I_m = nl.at_flux(npl.psi_rated_Wb, Ll)
        ac = ac_test(sc, npl, dc.R1_ohm, nl.L1_lowest, I_m, table, model, T2)
        Ll = ac.Ll_H
    M, _ = nl.at_flux(npl.psi_rated_Wb, Ll)
    L1 = M + Ll
    ident = {"R1_ohm": dc.R1_ohm, "R2_ohm": ac.R2_ohm, "Ll1_H": Ll, "Ll2_H": Ll, "M_H": M}
    acc = acceleration_test(sc, npl, ident, L1 / ac.R2_ohm, npl.power_W, table)
    psi, Lm = nl.magnetising_curve(Ll)
    identified = {
        "R1_ohm": dc.R1_ohm,
        "R2_ohm": ac.R2_ohm,
        "sigma_L1_H": L1 - M * M / L1,
        "L1_H": L1,
        "Ll_H": Ll,
        "M_H": M,
        "J_kgm2": acc.J_kgm2,
        "T2_step_s": T2,
        "magnetising": {"psi_Wb": psi.tolist(), "Lm_H": Lm.tolist()},
        "inverter_error": {"i_A": dc.i_A.tolist(), "u_V": dc.u_V.tolist()},
        "current_gain_b_per_a": dc.gain_b_per_a,
    }
    true = truth(sc, psi)
    durations = {
        "rotor-time": step.duration_s,
        "dc": dc.duration_s,
        "no-load": nl.duration_s,
        "ac": ac.duration_s,
        "acceleration": acc.duration_s,
    }
    return CommissioningResult(
        identified=identified,
        true=true,
        relative_error=relative_errors(identified, true, npl.psi_rated_Wb),
        durations_s=durations,
        wall_s=time.perf_counter() - t_wall,
        switched_off=switched_off(sc),
        nameplate={
            "I_rated_peak_A": npl.I_rated_A,
            "speed_rpm": npl.speed_rpm,
            "torque_Nm": npl.torque_Nm,
            "sources": npl.sources,
        },
        tests={"rotor-time": step, "dc": dc, "no-load": nl, "ac": ac, "acceleration": acc},
    )


def truth(sc: Scenario, psi_m: np.ndarray) -> dict:
    """The plant's values of the identified quantities (read from the plant: for the report
    only). The magnetising curve at the identified fluxes ``psi_m``; the inverter's loss per
    phase on its plateau, ``t_d f_sw Vdc + V_drop``."""
    m, sat, inv = sc.machine, sc.plant.saturation, sc.inverter
    L1, L2 = m.M_H + m.Ll1_H, m.M_H + m.Ll2_H
    if sat.enabled:
        rho, S = sat.rated_ratio, sat.exponent
        Lm0 = sat.Lm0_H if sat.Lm0_H is not None else m.M_H / rho
        psi_sat = sat.psi_sat_Wb or m.rated_flux_Wb * (rho / (1.0 - rho)) ** (1.0 / S)
        Lm = Lm0 / (1.0 + (np.asarray(psi_m) / psi_sat) ** S)
    else:
        Lm = np.full(len(psi_m), m.M_H)
    return {
        "R1_ohm": m.R1_ohm,
        "R2_ohm": m.R2_ohm,
        "sigma_L1_H": L1 - m.M_H**2 / L2,
        "L1_H": L1,
        "Ll1_H": m.Ll1_H,
        "Ll2_H": m.Ll2_H,
        "M_H": m.M_H,
        "J_kgm2": m.J_kgm2,
        "magnetising": {"psi_Wb": list(map(float, psi_m)), "Lm_H": Lm.tolist()},
        "current_gain_b_per_a": sc.sensor.gain_b / sc.sensor.gain_a,
        "inverter_error_plateau_V": inv.dead_time_s * inv.switching_frequency_Hz * inv.Vdc_V
        + inv.device_drop_V,
    }


def relative_errors(ident: dict, true: dict, psi_rated: float) -> dict:
    """``identified/true - 1`` of each quantity (module docstring of the result)."""
    out = {
        k: ident[k] / true[k] - 1.0
        for k in ("R1_ohm", "R2_ohm", "sigma_L1_H", "L1_H", "J_kgm2", "current_gain_b_per_a")
    }
    psi = np.array(ident["magnetising"]["psi_Wb"])
    err = np.array(ident["magnetising"]["Lm_H"]) / np.array(true["magnetising"]["Lm_H"]) - 1.0
    lo, hi = CURVE_RANGE_PU
    inside = (psi >= lo * psi_rated * 0.98) & (psi <= hi * psi_rated * 1.02)
    out["Lm_H"] = float(err[inside][np.argmax(np.abs(err[inside]))])
    u_true = true["inverter_error_plateau_V"]
    # an ideal inverter loses nothing: no relative error (None)
    u_id = ident["inverter_error"]["u_V"][-1]
    out["u_err_V"] = u_id / u_true - 1.0 if u_true > 0.0 else None
    return {k: (None if v is None else float(v)) for k, v in out.items()}


def identified_scenario(sc: Scenario, res: CommissioningResult) -> dict:
    """The input scenario with its controller's model replaced by the identified one (TOML-
    shaped, self-contained: the machine inlined, without ``preset`` or ``file``, so the file
    runs wherever it is moved): ``[estimator]`` R1, R2, leakages, M; the speed PI's gains
    from the identified J; the inverter's error as the dead-time feed-forward's assumed dead
    time (when the scenario compensates it) and, where the scenario has the section,
    ``[controller_model]``'s tables and the current sensors' relative gain (with ``ideal =
    false``: these, not the plant's).
    """
    from imdrive.config.perunit import speed_bandwidth_Hz
    from imdrive.design.gains import default_speed_gains

    ident = res.identified
    d = sc.to_dict()
    d["name"] = f"{sc.name[:85]}-commissioned"
    d["description"] = (
        f"{sc.name}, its controller's model from `imdrive commission` (R1, R2, leakage, M, "
        "J, magnetising curve, inverter error identified on this drive)"
    )
    # self-contained and movable: the machine inlined (every field is in the dict), with no
    # preset name beside the keys that override it and no path to a machine file
    d["machine"].pop("preset", None)
    d["machine"].pop("file", None)
    est = d["estimator"]
    for key in ("R1_ohm", "R2_ohm", "M_H"):
        est[key] = ident[key]
    est["Ll1_H"] = est["Ll2_H"] = ident["Ll_H"]
    est["R1_ratio"] = est["R2_ratio"] = est["M_ratio"] = None
    npl = nameplate(sc)
    ctl = d["control"]
    if ctl.get("speed_kp") is None:
        k_t = 1.5 * npl.n_p * ident["M_H"] / ident["L1_H"] * npl.psi_rated_Wb
        bw = speed_bandwidth_Hz(sc.with_overrides({"machine.J_kgm2": ident["J_kgm2"]}))
        kp, ki = default_speed_gains(ident["J_kgm2"], k_t, 2.0 * math.pi * bw)
        ctl["speed_kp"], ctl["speed_ki"] = kp, ki
    if ctl.get("dead_time_compensation") == "feedforward":
        ctl["dead_time_compensation_s"] = ident["inverter_error"]["u_V"][-1] / (
            sc.inverter.switching_frequency_Hz * npl.Vdc_meas_V
        )
    if "controller_model" in SECTIONS:
        cm = d.setdefault("controller_model", {})
        # the identified model, not the plant's: ideal = true would replace the tables on
        # reading (until 2026-11-30 a commissioned realistic preset ran the ideal tables)
        cm["ideal"] = False
        cm["magnetising_psi_Wb"] = ident["magnetising"]["psi_Wb"]
        cm["magnetising_Lm_H"] = ident["magnetising"]["Lm_H"]
        cm["inverter_error_i_A"] = ident["inverter_error"]["i_A"]
        cm["inverter_error_u_V"] = ident["inverter_error"]["u_V"]
        cm["current_gain_b_per_a"] = ident["current_gain_b_per_a"]
    return d


#: the files :func:`write_outputs` writes (the folder rule's ``owns``)
COMMISSION_FILES = ("summary.json", "identified.toml")


def owns_commission_file(name: str) -> bool:
    """Whether ``name`` is a file ``imdrive commission`` writes (``summary.json``,
    ``identified.toml``, its PNG figures)."""
    return name in COMMISSION_FILES or name.endswith(".png")


def write_outputs(sc: Scenario, res: CommissioningResult, out) -> None:
    """``summary.json``, ``identified.toml`` and the figures as the folder ``out``.

    The folder is replaced as a whole (:func:`imdrive._io.replace_folder`, as ``imdrive run``
    writes its own): the files are written into a staging folder beside it, which then takes
    its place, so a second commissioning killed while it draws its figures leaves the first
    one's folder as it was, never a folder that mixes two runs.
    """
    from imdrive._io import replace_folder
    from imdrive.commission.figures import save_figures
    from imdrive.config.summary_file import portable_scenario, portable_summary
    from imdrive.config.toml_writer import dumps

    data = identified_scenario(sc, res)
    Scenario.from_dict(data)  # what is written must run
    summary = res.summary()
    summary["controller_model_keys"] = "controller_model" in SECTIONS
    summary["scenario"] = sc.to_dict()
    with replace_folder(Path(out)) as staging:
        summary = portable_summary(summary, staging)  # staging: beside the folder
        data = portable_scenario(data, staging)
        save_figures(res, staging)
        (staging / "summary.json").write_text(json.dumps(summary, indent=2, default=float))
        (staging / "identified.toml").write_text(dumps(data))
