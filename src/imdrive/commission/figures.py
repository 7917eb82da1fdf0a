"""Figures of the identification run, one PNG per test."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imdrive._figure import new_figure, save_png


def save_figures(res, out) -> list[Path]:
    """Write ``dc.png``, ``no-load.png``, ``ac.png``, ``acceleration.png`` into ``out``."""
    out = Path(out)
    t = res.tests
    paths = []
    dc = t["dc"]
    fig = new_figure(figsize=(9, 3.5), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    ax1.plot(dc.I_A, dc.V_V, "o", label="measured levels")
    ax1.plot(dc.I_A, dc.R1_ohm * dc.I_A + dc.e_inf_V, "-", label=f"R1 = {dc.R1_ohm:.4g} ohm")
    ax1.set(xlabel="alpha current (A)", ylabel="commanded alpha voltage (V)", title="DC test")
    ax1.legend()
    ax2.plot(dc.i_A, dc.u_V, "o-")
    ax2.set(
        xlabel="phase current (A)",
        ylabel="voltage lost per phase (V)",
        title="inverter error table",
        xscale="symlog",
        xlim=(0, None),
    )
    paths.append(_save(fig, out / "dc.png"))
    psi, Lm = res.identified["magnetising"]["psi_Wb"], res.identified["magnetising"]["Lm_H"]
    fig = new_figure(figsize=(5, 3.5), layout="constrained")
    ax = fig.subplots()
    ax.plot(psi, Lm, "o-", label="identified")
    ax.plot(
        res.true["magnetising"]["psi_Wb"], res.true["magnetising"]["Lm_H"], "k--", label="plant"
    )
    ax.set(xlabel="magnetising flux (Wb)", ylabel="Lm (H)", title="no-load test")
    ax.legend()
    paths.append(_save(fig, out / "no-load.png"))
    ac = t["ac"]
    fig = new_figure(figsize=(5, 3.5), layout="constrained")
    ax = fig.subplots()
    f = ac.w / (2 * np.pi)
    ax.plot(f, ac.Z.real, "o", label="Re Z measured")
    ax.plot(f, ac.Z.imag, "s", label="Im Z measured")
    ax.plot(f, ac.Z_fit.real, "-", f, ac.Z_fit.imag, "-")
    ax.set(xlabel="frequency (Hz)", ylabel="impedance (ohm)", title="standstill AC test")
    ax.legend()
    paths.append(_save(fig, out / "ac.png"))
    acc = t["acceleration"]
    r = acc.result
    fig = new_figure(figsize=(6, 3.5), layout="constrained")
    ax = fig.subplots()
    col = "speed_est_rpm" if "speed_est_rpm" in r.columns else "speed_rpm"
    ax.plot(r["time_s"], r[col], label="speed the drive uses")
    ax.plot(r["time_s"], r["speed_ref_rpm"], "k:", label="reference")
    for k, (a, b) in enumerate(acc.windows):
        ax.axvspan(a, b, alpha=0.2, color="C1" if k else "C0")
    ax.set(
        xlabel="time (s)",
        ylabel="speed (rpm)",
        title=f"acceleration test: J = {acc.J_kgm2:.4g} kg m²",
    )
    ax.legend()
    paths.append(_save(fig, out / "acceleration.png"))
    return paths


def _save(fig, path: Path) -> Path:
    return save_png(fig, path, dpi=100)  # by the output rule for one file
