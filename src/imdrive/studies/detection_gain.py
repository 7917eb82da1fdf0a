"""Whether the R2 detection reads R2 with the sign its law assumes: the measured in-phase gain of
the recommended drive's detection while regenerating at low stator frequency, against analytic
models of it.

The model-based law (:mod:`imdrive.kernels.r2_kalman`) turns each window's detected flux error
``E`` into a relative R2 error ``r = -E / (L a S)``, with ``S = S(w_i T2)`` the in-phase
sensitivity of a rotor flux answering the injected flux current alone
(:func:`imdrive.kernels.sensitivity.in_phase_sensitivity`), or, where both of the
injection's side bands lie under the detection filter's corner, by the *decoupled* model
below (:func:`imdrive.kernels.r2_kalman.law_response`; Krause 500 hp at +1 Hz, measured gain
0.03 against 0.15-0.17). This study measures what the detection gives. Each cell runs
``injection-robust`` (the adaptive observer, the detection's own pair of flux models,
:mod:`imdrive.kernels.flux_detector`) regenerating the
rated torque at the stator frequency ``f_s`` (the speed from
:func:`imdrive.studies.zero_frequency.speed_for_stator_frequency`), twice, with R2_hat pinned at
:data:`PIN` below and above R2 (both clamps within 1e-4 of R2_hat(0)); the law's own reading of
each run is ``r_meas = -E / (L a S)`` with ``E`` the mean demodulated error over the last
:data:`TAIL` of the run, and the measured gain is

    g = (r_meas(+) - r_meas(-)) / (r(+) - r(-))

1 where the law's model holds; between 0 and 1 the law only slows; **below 0 the law walks R2_hat
away from R2** (a run from R2_hat(0) off then ends at a clamp or loses control). Two injections:
the drive's own schedule (its first frequency and the gating's choice of harmonics,
:mod:`imdrive.kernels.gating`) and the first frequency alone (``compensator.gate_band_pu = 0``).

The two model columns, per unit of ``S`` (:func:`model_gains`), are the in-phase response of
:mod:`imdrive.kernels.detection_response`: *decoupled* (the detection's speed correction or
slip decoupling holds the q-axis error at zero), and the *worst* of that and the slip-coupled
response (the current model running at a speed that carries the R2 error's slip error, the
detector's speed correction off while regenerating below the rated slip frequency), which is
what the injection's frequency schedule weighs there
(:func:`imdrive.kernels.gating.injection_by_response`). Both include the comparison filter's
effect on the side bands.

``python -m imdrive.studies.doctables --run detection-gain`` measures it again and rewrites its
table in docs/machine-envelope.md.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pandas as pd

from imdrive.config.machine import machine_preset, rated_point
from imdrive.errors import ConfigWarning
from imdrive.studies import zero_frequency

#: Machines: the paper's, and the two of the zero-frequency study whose regenerating runs
#: miss (Krause 50 hp: 5 % rated slip; Krause 500 hp: 1.5 %).
MACHINES = ("paper-table-iv", "krause-50hp", "krause-500hp")
#: Stator frequencies of the steady state with R2_hat = R2, Hz.
F_S_HZ = (-0.25, 0.5, 2.0)
#: R2_hat/R2 of the two runs of a cell.
PIN = (0.95, 1.05)
#: The injections: the drive's own schedule, and its first frequency alone.
INJECTIONS = {"schedule": [], "first": ["compensator.gate_band_pu = 0.0"]}
#: The share of the run, at its end, whose mean demodulated error is the run's ``E``.
TAIL = 0.4
#: A measured gain below this reads R2 with the wrong sign.
WRONG_SIGN = 0.0


def model_gains(w_i, T2, w_sl, w_e, wc) -> tuple[float, float]:
    """The modelled in-phase response per unit of ``S``: decoupled, and the smaller of the
    decoupled and the slip-coupled one, what the frequency schedule weighs while regenerating
    below the rated slip frequency
    (:func:`imdrive.kernels.detection_response.in_phase_response`, whose arguments these are;
    module docstring).
    """
    from imdrive.kernels.detection_response import in_phase_response
    from imdrive.kernels.sensitivity import in_phase_sensitivity

    S = in_phase_sensitivity(w_i, T2)
    return (
        in_phase_response(w_i, T2, w_sl, w_e, wc, False) / S,
        in_phase_response(w_i, T2, w_sl, w_e, wc, True) / S,
    )


def scenarios(machines=MACHINES, frequencies=F_S_HZ):
    """The cells' scenarios and their table (machine, f_s target, injection, R2_hat/R2)."""
    scs, rows = [], []
    for m in machines:
        for inj, extra in INJECTIONS.items():
            for ratio in PIN:
                pin = [
                    *extra,
                    "compensator.R2_min_ratio = 0.9999",
                    "compensator.R2_max_ratio = 1.0001",
                ]
                cell_scs, table = zero_frequency.scenarios(
                    [m], frequencies, (ratio,), drives=("injection-robust",)
                )
                for sc, (_, row) in zip(cell_scs, table.iterrows(), strict=True):
                    scs.append(sc.with_overrides(pin))
                    rows.append(
                        {
                            "machine": m,
                            "f_s_target_Hz": row["f_s_target_Hz"],
                            "injection": inj,
                            "R2_ratio": ratio,
                        }
                    )
    return scs, pd.DataFrame(rows)


def _reading(sc, log) -> dict:
    """One run's tail means (``log``: its :class:`~imdrive.run.result.SimulationResult`): the
    demodulated error, R2_hat/R2, the stator and injection frequencies, and the law's reading
    ``r_meas = -E / (L a S)``."""
    from imdrive.config.perunit import resolve
    from imdrive.kernels.sensitivity import in_phase_sensitivity

    t = log.time_s
    tail = t >= t[-1] * (1.0 - TAIL)
    th = np.unwrap(log["theta_e_rad"])
    w_e = float(np.mean(np.gradient(th, t)[tail]))
    f_i = float(np.mean(log["inj_freq_Hz"][tail]))
    R2_hat = float(np.mean(log["R2_hat_ohm"][tail]))
    D = resolve(sc)
    T2_hat = (D.M_hat + D.Ll2_hat) / R2_hat
    S = in_phase_sensitivity(2.0 * math.pi * f_i, T2_hat)
    E = float(np.mean(log["e_d0_demod_Wb"][tail]))
    return {
        "E_Wb": E,
        "r": R2_hat / float(np.mean(log["R2_ohm"][tail])) - 1.0,
        "r_meas": -E / (D.M_hat * D.inj_amp * S),
        "f_s_Hz": w_e / (2.0 * math.pi),
        "f_inj_Hz": f_i,
    }


def measure(machines=MACHINES, frequencies=F_S_HZ) -> pd.DataFrame:
    """Run the cells; one row per cell (machine, f_s, injection) with the measured gain and
    the two models' (module docstring)."""
    from imdrive.run.batch import simulate_batch
    from imdrive.run.compensator_blocks import flux_filter_rad_s

    scs, table = scenarios(machines, frequencies)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConfigWarning)
        res = simulate_batch(scs, logs=True)
    readings = [_reading(sc, r) for sc, r in zip(scs, res.results, strict=True)]
    runs = pd.concat([table, pd.DataFrame(readings)], axis=1)
    out = []
    for (m, f, inj), g in runs.groupby(["machine", "f_s_target_Hz", "injection"], sort=False):
        lo, hi = g.sort_values("R2_ratio").iloc[0], g.sort_values("R2_ratio").iloc[-1]
        sc = scs[int(g.index[0])]
        rp = rated_point(machine_preset(m))
        mach = machine_preset(m)
        T2 = (mach.M_H + mach.Ll2_H) / mach.R2_ohm
        w_sl = -2.0 * math.pi * rp.frequency_Hz * rp.slip  # regenerating the rated torque
        f_s = 0.5 * (lo["f_s_Hz"] + hi["f_s_Hz"])
        f_i = 0.5 * (lo["f_inj_Hz"] + hi["f_inj_Hz"])
        dec, cpl = model_gains(
            2.0 * math.pi * f_i, T2, w_sl, 2.0 * math.pi * f_s, flux_filter_rad_s(sc)
        )
        out.append(
            {
                "machine": m,
                "f_s_target_Hz": f,
                "injection": inj,
                "f_s_Hz": f_s,
                "f_inj_Hz": f_i,
                "below_rated_slip": abs(f_s) < rp.frequency_Hz * rp.slip,
                "gain": (hi["r_meas"] - lo["r_meas"]) / (hi["r"] - lo["r"]),
                "model_decoupled": dec,
                "model_worst": cpl,
            }
        )
    return pd.DataFrame(out)


def _signed(v: float) -> str:
    return f"{v:+.2f}".replace("-", "−")


def markdown_lines(df: pd.DataFrame) -> list[str]:
    """The table of docs/machine-envelope.md, "Where the detection reads R2"."""
    lines = [
        "| machine | f_s, Hz | injection | f_inj, Hz | below rated slip | measured gain "
        "| model: decoupled | model: worst of both |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for _, r in df.iterrows():
        g = _signed(r["gain"])
        if r["gain"] < WRONG_SIGN:
            g = f"**{g}**"
        below = "yes" if r["below_rated_slip"] else "no"
        lines.append(
            f"| {r['machine']} | {_signed(r['f_s_Hz'])} | {r['injection']} "
            f"| {r['f_inj_Hz']:.2f} | {below} | {g} | {_signed(r['model_decoupled'])} "
            f"| {_signed(r['model_worst'])} |"
        )
    return lines
