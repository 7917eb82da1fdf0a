"""Figures of a run, drawn with matplotlib's object API (no global pyplot state, Agg-safe)."""

from __future__ import annotations

from pathlib import Path

from matplotlib.figure import Figure


def _fig(nrows: int, title: str) -> tuple[Figure, list]:
    fig = Figure(figsize=(8, 2.4 * nrows + 0.6), layout="constrained")
    axes = fig.subplots(nrows, 1, sharex=True, squeeze=False)[:, 0]
    fig.suptitle(title)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time (s)")
    return fig, list(axes)


def speed_figure(res) -> Figure:
    s = res.signals
    t = s["time_s"]
    fig, (ax,) = _fig(1, f"{res.scenario.name}: speed")
    ax.plot(t, s["speed_rpm"], label="actual")
    if "speed_ref_rpm" in s:
        ax.plot(t, s["speed_ref_rpm"], "--", label="reference")
        if res.scenario.control.speed_feedback == "mras":
            ax.plot(t, s["speed_est_rpm"], ":", label="estimated (MRAS)")
    ax.set_ylabel("speed (rpm)")
    ax.legend(loc="best")
    return fig


def torque_figure(res) -> Figure:
    s = res.signals
    fig, (ax,) = _fig(1, f"{res.scenario.name}: torque")
    ax.plot(s["time_s"], s["torque_Nm"], label="electromagnetic")
    ax.plot(s["time_s"], s["load_torque_Nm"], "--", label="load")
    ax.set_ylabel("torque (N m)")
    ax.legend(loc="best")
    return fig


def currents_figure(res) -> Figure:
    s = res.signals
    t = s["time_s"]
    vector = "i_d_A" in s
    fig, axes = _fig(2 if vector else 1, f"{res.scenario.name}: stator currents")
    for ph in "abc":
        axes[0].plot(t, s[f"i_{ph}_A"], lw=0.8, label=f"i_{ph}")
    axes[0].set_ylabel("phase current (A)")
    axes[0].legend(loc="best")
    if vector:
        axes[1].plot(t, s["i_d_A"], label="i_d")
        axes[1].plot(t, s["id_ref_A"], "--", label="i_d*")
        axes[1].plot(t, s["i_q_A"], label="i_q")
        axes[1].plot(t, s["iq_ref_A"], "--", label="i_q*")
        axes[1].set_ylabel("synchronous frame (A)")
        axes[1].legend(loc="best")
    return fig


def estimator_figure(res) -> Figure:
    s = res.signals
    t = s["time_s"]
    fig, axes = _fig(3, f"{res.scenario.name}: flux and MRAS")
    axes[0].plot(t, s["flux_Wb"], label="|psi_r| (plant)")
    axes[0].set_ylabel("rotor flux (Wb)")
    axes[0].legend(loc="best")
    axes[1].plot(t, s["e_d0_Wb"], label="e_d0")
    axes[1].plot(t, s["e_q0_Wb"], label="e_q0")
    axes[1].set_ylabel("flux error (Wb)")
    axes[1].legend(loc="best")
    axes[2].plot(t, s["R2_ohm"], label="R2 (plant)")
    axes[2].plot(t, s["R2_est_ohm"], "--", label="R2 estimate")
    axes[2].set_ylabel("rotor resistance (ohm)")
    axes[2].legend(loc="best")
    return fig


def compensation_figure(res) -> Figure:
    """The paper's Figs. 5/6 layout: e_d0, the R2 estimate, and the motor speed over time."""
    s = res.signals
    t = s["time_s"]
    comp = res.scenario.compensator
    fig, axes = _fig(3, f"{res.scenario.name}: rotor-resistance compensation")
    if comp.input == "demodulated":
        axes[0].plot(t, s["e_d0_Wb"], lw=0.6, alpha=0.6, label="e_d0")
        axes[0].plot(t, s["e_d0_demod_Wb"], lw=0.6, label="2 e_d0 sin(injection)")
    else:
        axes[0].plot(t, s["e_d0_Wb"], label="e_d0")
    axes[0].set_ylabel("flux error (Wb)")
    axes[0].legend(loc="best")
    axes[1].plot(t, s["R2_ohm"], label="R2 (plant)")
    axes[1].plot(t, s["R2_est_ohm"], "--", label="R2 estimate")
    axes[1].set_ylabel("rotor resistance (ohm)")
    axes[1].legend(loc="best")
    axes[2].plot(t, s["speed_rpm"], label="actual")
    axes[2].plot(t, s["speed_ref_rpm"], "--", label="reference")
    axes[2].plot(t, s["speed_est_rpm"], ":", label="estimated (MRAS)")
    ref = s["speed_ref_rpm"][-1]
    axes[2].set_ylim(ref - 30 - 0.05 * abs(ref), ref + 30 + 0.05 * abs(ref))
    axes[2].set_ylabel("speed (rpm)")
    axes[2].legend(loc="best")
    for ax in axes:
        ax.axvline(comp.t_on_s, color="0.5", lw=0.8, ls="-.")
    return fig


def save_figures(res, out_dir) -> list[Path]:
    """Write the run's PNG figures into ``out_dir``; returns their paths."""
    out = Path(out_dir)
    figs = {
        "speed.png": speed_figure(res),
        "torque.png": torque_figure(res),
        "currents.png": currents_figure(res),
    }
    if "e_d0_Wb" in res.signals:
        figs["estimator.png"] = estimator_figure(res)
        if res.scenario.compensator.enabled:
            figs["compensation.png"] = compensation_figure(res)
    paths = []
    for name, fig in figs.items():
        fig.savefig(out / name, dpi=110)
        paths.append(out / name)
    return paths


def _default_groups(res) -> list[list[str]]:
    cols = set(res.columns)
    groups = [[c for c in ("speed_rpm", "speed_ref_rpm", "speed_est_rpm") if c in cols]]
    groups.append([c for c in ("torque_Nm", "load_torque_Nm") if c in cols])
    groups.append([c for c in ("i_alpha_A", "i_beta_A") if c in cols])
    if "e_d0_Wb" in cols:
        groups.append(["e_d0_Wb"])
        groups.append(["R2_est_ohm", "R2_ohm"])
    return [g for g in groups if g]


def result_figure(res, signals=None, t0: float = 0.0, t1=None) -> Figure:
    """Figure of a result: given columns one panel each, or the default groups (see
    :meth:`imdrive.run.result.SimulationResult.plot`)."""
    unknown = [s for s in (signals or []) if s not in res.signals]
    if unknown:
        raise KeyError(f"no such column(s) {unknown}; see res.columns")
    groups = [[s] for s in signals] if signals else _default_groups(res)
    w = res.window(t0, t1)
    fig, axes = _fig(len(groups), res.scenario.name)
    for ax, group in zip(axes, groups, strict=True):
        for name in group:
            ax.plot(w["time_s"], w[name], lw=0.9, label=name)
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time, s")
    return fig
