"""Figures of a run, drawn with matplotlib's object API (no global pyplot state, Agg-safe).

Conventions shared by every figure of the package (run figures, the paper's reproduction,
sweep heatmaps, report.html):

* one display unit per quantity (:data:`DISPLAY_UNITS`): flux linkages in mWb (SI Wb inside,
  scaled only here), speeds in rpm, torques in N m, currents in A, resistances in Ω; axis
  labels read ``quantity (unit)`` and flux axes never carry a hidden offset or multiplier;
* legends say what a signal is (:data:`SIGNALS`: "estimated speed (MRAS)",
  "rotor-resistance estimate R̂2"), not its column name;
* a flux error whose start-up transient is a hundred times its steady value (e_d0) gets a
  second, zoomed panel whose y-range comes from the steady-state samples
  (:func:`zoom_limits`, :func:`steady_start`), and the compensator's switch-on is marked.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from imdrive.config.compensator import demodulated_input
from imdrive.config.sequence import sequence
from imdrive.run.columns import current_name
from imdrive.run.export import unit_of
from imdrive.run.metrics import compensator_start_s

if TYPE_CHECKING:  # matplotlib is loaded by the first figure, not by the tables below
    from imdrive._figure import DisplayFigure as Figure

#: flux linkages are drawn in mWb: the start-up transient (tens of mWb), the rotor flux
#: (hundreds) and the steady e_d0 bias (a few µWb to a few mWb) all read without a multiplier
FLUX_UNIT = "mWb"
FLUX_SCALE = 1e3

#: the unit each quantity is drawn in, keyed by the column's SI unit suffix:
#: ``column unit -> (display unit, factor from the column's unit)``
DISPLAY_UNITS = {
    "Wb": (FLUX_UNIT, FLUX_SCALE),
    "rpm": ("rpm", 1.0),
    "Nm": ("N m", 1.0),
    "A": ("A", 1.0),
    "ohm": ("Ω", 1.0),
    "V": ("V", 1.0),
    "C": ("°C", 1.0),
    "rad/s": ("rad/s", 1.0),
    "rad": ("rad", 1.0),
    "s": ("s", 1.0),
}

#: the quantity of each column unit, for axis labels ``quantity (display unit)``
QUANTITIES = {
    "Wb": "flux linkage",
    "rpm": "speed",
    "Nm": "torque",
    "A": "current",
    "ohm": "resistance",
    "V": "voltage",
    "C": "temperature",
    "rad/s": "speed",
    "rad": "angle",
    "s": "time",
}

#: what each column is, for legends: ``column -> label``
SIGNALS = {
    "speed_rpm": "actual speed",
    "speed_ref_rpm": "speed reference",
    "speed_est_rpm": "estimated speed",
    "w_m_rad_s": "actual speed",
    "torque_Nm": "electromagnetic torque",
    "load_torque_Nm": "load torque",
    "i_a_A": "phase a current",
    "i_b_A": "phase b current",
    "i_c_A": "phase c current",
    "i_alpha_A": "stator current, α axis",
    "i_beta_A": "stator current, β axis",
    "i_alpha_meas_A": "measured stator current, α axis",
    "i_beta_meas_A": "measured stator current, β axis",
    "i_d_A": "flux current i_d",
    "id_ref_A": "flux-current reference i_d*",
    "i_q_A": "torque current i_q",
    "iq_ref_A": "torque-current reference i_q*",
    "flux_Wb": "rotor flux magnitude |ψr| (plant)",
    "psi_r_alpha_Wb": "rotor flux, α axis (plant)",
    "psi_r_beta_Wb": "rotor flux, β axis (plant)",
    "e_d0_Wb": "MRAS flux error, d axis (e_d0)",
    "e_q0_Wb": "MRAS flux error, q axis (e_q0)",
    "e_d0_demod_Wb": "e_d0 detected synchronously with the injection",
    "lam_v_alpha_Wb": "voltage-model rotor flux, α axis",
    "lam_v_beta_Wb": "voltage-model rotor flux, β axis",
    "lam_i_alpha_Wb": "current-model rotor flux, α axis",
    "lam_i_beta_Wb": "current-model rotor flux, β axis",
    "R2_ohm": "actual R2 (plant)",
    "R2_hat_ohm": "rotor-resistance estimate R̂2",
    "R1_ohm": "actual R1 (plant)",
    "R1_hat_ohm": "stator-resistance estimate R̂1",
    "v_alpha_V": "applied voltage, α axis",
    "v_beta_V": "applied voltage, β axis",
    "v_ref_alpha_V": "voltage reference, α axis",
    "v_ref_beta_V": "voltage reference, β axis",
    "theta1_C": "stator winding temperature",
    "theta2_C": "rotor winding temperature",
    "theta_e_rad": "field angle of the controller",
}


def estimator_legend(speed_feedback: str) -> str:
    """The legend name of the estimator ``speed_feedback`` selects (its settings class's
    ``legend``, :func:`imdrive.config.registry.estimator_settings`); the name itself for
    ``"measured"`` or an unknown one."""
    from imdrive.config.registry import ESTIMATOR_SETTINGS

    cls = ESTIMATOR_SETTINGS.get(speed_feedback) if speed_feedback != "measured" else None
    return getattr(cls, "estimator_legend", speed_feedback)


#: the speed estimators' names in legends, by ``control.speed_feedback`` (the package's, at
#: import; kept for imdrive 0.2 callers: :func:`estimator_legend` also knows plug-ins)
ESTIMATOR_NAMES = {
    name: estimator_legend(name) for name in ("mras", "reactive-mras", "smo-mras", "afo", "ekf")
}


def display_unit(column: str) -> tuple[str, float]:
    """``(unit, factor)``: the unit column ``column`` is drawn in and the factor from its SI
    (column) unit; flux linkages in mWb (:data:`DISPLAY_UNITS`)."""
    return DISPLAY_UNITS.get(unit_of(column), (unit_of(column), 1.0))


def signal_label(column: str, res=None) -> str:
    """What column ``column`` is, for a legend (its name when unknown); the speed estimate is
    named after the run's estimator when ``res`` is given."""
    label = SIGNALS.get(column, column)
    if column == "speed_est_rpm" and res is not None:
        fb = res.scenario.control.speed_feedback
        label = f"{label} ({estimator_legend(fb)})"
    return label


def zoom_limits(values, q: float = 0.5, pad: float = 0.15) -> tuple[float, float]:
    """y-limits showing ``values`` without their outliers, zero included.

    Parameters
    ----------
    values : array_like
        The samples to show (in the unit they are drawn in), e.g. a steady-state window.
    q : float
        Percentile, %, cut at each end (robust to a few spikes).
    pad : float
        Margin on each side, as a fraction of the span.

    Returns
    -------
    (float, float)
        ``(lo, hi)`` spanning the ``q`` .. ``100 - q`` percentiles and 0 (a steady bias is
        read against zero), widened by ``pad``; ``(-1, 1)`` without a finite sample.
    """
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return -1.0, 1.0
    lo, hi = np.percentile(v, [q, 100.0 - q])
    lo, hi = min(float(lo), 0.0), max(float(hi), 0.0)
    span = hi - lo
    if span == 0.0:  # all zero
        return -1.0, 1.0
    return lo - pad * span, hi + pad * span


def data_limits(values, pad: float = 0.05) -> tuple[float, float]:
    """y-limits that fit ``values``: their finite range, widened on each side by ``pad`` of
    the span or of the largest magnitude, whichever is more.

    The magnitude term is for a (nearly) constant signal: a plant's R2 and an estimate that is
    not adapted. Left to itself plotly.js spans a constant ``v`` as ``v - 1 .. v + 1`` (ticks
    -0.5 .. 1 ohm for an R2 of 0.145 ohm); here it is ``0.95 v .. 1.05 v``.

    Parameters
    ----------
    values : array_like
        The samples to show, in the unit they are drawn in.
    pad : float
        Margin on each side, as a fraction of ``max(hi - lo, max |v|)``.

    Returns
    -------
    (float, float)
        ``(lo - m, hi + m)`` with ``m = pad * max(hi - lo, max |v|)``; ``(-1, 1)`` when there
        is no finite sample or all are zero.
    """
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return -1.0, 1.0
    lo, hi = float(v.min()), float(v.max())
    m = pad * max(hi - lo, abs(lo), abs(hi))
    if m == 0.0:  # all zero
        return -1.0, 1.0
    return lo - m, hi + m


def steady_start(res) -> float:
    """Start of the steady-state window of a run, s: where the compensator switches on when it
    is enabled (the presets switch it on once the start-up has settled); otherwise 1 s after
    the last change of the speed reference or the load, at least half-way through and at most
    90 % of the run."""
    sc = res.scenario
    t_end = float(res.time_s[-1])
    t_on = compensator_start_s(res)
    if "R2_hat_ohm" in res.signals and t_on < t_end:
        return t_on
    seq = sequence(sc)
    last = max(seq.speed_ref_rpm.points[-1][0], seq.load_Nm.points[-1][0])
    return min(max(last + 1.0, 0.5 * t_end), 0.9 * t_end)


def _fig(nrows: int, title: str, heights=None, sharex: bool = True) -> tuple[Figure, list]:
    from imdrive._figure import DisplayFigure as Figure

    fig = Figure(figsize=(8, 2.4 * nrows + 0.6), layout="constrained")
    axes = fig.subplots(
        nrows, 1, sharex=sharex, squeeze=False, gridspec_kw={"height_ratios": heights}
    )[:, 0]
    fig.suptitle(title)
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelbottom=True)  # every panel its time axis, not only the last
    axes[-1].set_xlabel("time (s)")
    return fig, list(axes)


def _plot(ax, res, column: str, *args, **kwargs):
    """Plot one column against time in its display unit, labelled with what it is."""
    s = res.signals
    _, k = display_unit(column)
    kwargs.setdefault("label", signal_label(column, res))
    return ax.plot(s["time_s"], np.asarray(s[column]) * k, *args, **kwargs)


def _ylabel(ax, quantity: str, column: str) -> None:
    unit, _ = display_unit(column)
    ax.set_ylabel(f"{quantity} ({unit})")
    if unit == FLUX_UNIT:  # the label is the whole truth: no offset, no 1e-3 multiplier
        ax.ticklabel_format(axis="y", style="plain", useOffset=False)


def _mark_switch_on(axes, res) -> None:
    """A vertical line on every panel at the compensator's switch-on, labelled on the first."""
    t_on = compensator_start_s(res)
    if t_on >= res.time_s[-1]:
        return
    for ax in axes:
        ax.axvline(t_on, color="0.35", lw=0.9, ls="-.")
    axes[0].text(
        t_on,
        0.97,
        f" compensator on ({t_on:.4g} s)",
        transform=axes[0].get_xaxis_transform(),
        ha="left",
        va="top",
        fontsize=8,
        color="0.25",
    )


def _zoom_panel(ax, res, columns, t0: float) -> None:
    """``columns`` again, y-range from the samples at ``t >= t0`` (:func:`zoom_limits`), drawn
    from where they settle into that range for good (the transient before it is left out
    rather than clipped), with the steady window shaded and a zero line."""
    s = res.signals
    t = np.asarray(s["time_s"])
    win = t >= t0
    scaled = {col: np.asarray(s[col]) * display_unit(col)[1] for col, _ in columns}
    lo, hi = zoom_limits(np.concatenate([v[win] for v in scaled.values()]))
    outside = np.zeros(t.shape, dtype=bool)
    for v in scaled.values():
        outside |= ~((v >= lo) & (v <= hi))
    outside &= ~win
    first = int(np.flatnonzero(outside)[-1]) + 1 if outside.any() else 0
    for col, style in columns:
        kw = {"label": signal_label(col, res), **style}
        ax.plot(t[first:], scaled[col][first:], **kw)
    ax.set_ylim(lo, hi)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.axvspan(t0, float(t[-1]), color="tab:green", alpha=0.06, lw=0)
    ax.set_title(
        f"zoom on the steady state: y-range from the samples after {t0:g} s (shaded)",
        fontsize=8,
        loc="left",
    )


def speed_figure(res) -> Figure:
    s = res.signals
    fig, (ax,) = _fig(1, f"{res.scenario.name}: speed")
    _plot(ax, res, "speed_rpm")
    if "speed_ref_rpm" in s:
        _plot(ax, res, "speed_ref_rpm", "--")
        if res.scenario.control.speed_feedback != "measured":
            _plot(ax, res, "speed_est_rpm", ":")
    _ylabel(ax, "speed", "speed_rpm")
    ax.legend(loc="best")
    return fig


def torque_figure(res) -> Figure:
    fig, (ax,) = _fig(1, f"{res.scenario.name}: torque")
    _plot(ax, res, "torque_Nm")
    _plot(ax, res, "load_torque_Nm", "--")
    _ylabel(ax, "torque", "torque_Nm")
    ax.legend(loc="best")
    return fig


#: a run with more electrical periods than this gets the envelope of its phase currents and a
#: zoom window on its last periods in ``currents.png`` (three lines of hundreds of periods are a
#: solid block)
LONG_RUN_PERIODS = 40
#: electrical periods in the zoom window of a long run
ZOOM_PERIODS = 4


def electrical_periods(res) -> float:
    """Electrical periods of the stator currents over the run: ∫|ω_e| dt / 2π, with ω_e from
    the angle of the stator current vector."""
    s = res.signals
    if "i_alpha_A" not in s or len(s["time_s"]) < 2:
        return 0.0
    angle = np.unwrap(np.angle(np.asarray(s["i_alpha_A"]) + 1j * np.asarray(s["i_beta_A"])))
    return float(np.sum(np.abs(np.diff(angle))) / (2 * np.pi))


def currents_figure(res) -> Figure:
    """Phase currents (a long run: their envelope ±|i_s| and a zoom on the last periods) and,
    for a vector drive, the synchronous-frame currents against their references; the legends
    beside the panels, not over the data."""
    vector = "i_d_A" in res.signals
    periods = electrical_periods(res)
    long_run = periods > LONG_RUN_PERIODS
    n = (2 if vector else 1) + long_run
    fig, axes = _fig(n, f"{res.scenario.name}: stator currents", sharex=not long_run)
    if long_run and vector:  # the whole-run panels share the time axis, the zoom has its own
        axes[-1].sharex(axes[0])
    s = res.signals
    t = np.asarray(s["time_s"])
    if long_run:
        mag = np.hypot(s["i_alpha_A"], s["i_beta_A"])
        axes[0].fill_between(t, -mag, mag, color="tab:blue", alpha=0.25, lw=0,
                             label="phase currents (envelope ±|i_s|)")  # fmt: skip
        axes[0].plot(t, mag, color="tab:blue", lw=0.8, label="stator current magnitude |i_s|")
        t1 = float(t[-1])
        t0 = max(t1 - ZOOM_PERIODS * t1 / periods, float(t[0]))
        axes[0].axvspan(t0, t1, color="tab:orange", alpha=0.15, lw=0, label="zoom below")
        w = t >= t0
        for ph in "abc":
            _plot(axes[1], res, f"i_{ph}_A", lw=0.9)
        axes[1].set_xlim(t0, t1)
        lo, hi = zoom_limits(np.concatenate([np.asarray(s[f"i_{ph}_A"])[w] for ph in "abc"]))
        axes[1].set_ylim(lo, hi)
        axes[1].set_title(f"zoom: the last {t1 - t0:.3g} s (shaded above)", fontsize=8, loc="left")
        _ylabel(axes[1], "phase current", "i_a_A")
        axes[1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    else:
        for ph in "abc":
            _plot(axes[0], res, f"i_{ph}_A", lw=0.8)
    _ylabel(axes[0], "phase current", "i_a_A")
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    if vector:
        axes = [axes[0], axes[-1]]
        for col, style in (("i_d_A", "-"), ("id_ref_A", "--"), ("i_q_A", "-"), ("iq_ref_A", "--")):
            _plot(axes[1], res, col, style)
        _ylabel(axes[1], "synchronous-frame current", "i_d_A")
        axes[1].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    return fig


def estimator_figure(res) -> Figure:
    """Rotor flux, the MRAS flux errors (whole run and a steady-state zoom), R̂2 against R2."""
    fig, axes = _fig(4, f"{res.scenario.name}: flux and MRAS", heights=[1, 1, 1.3, 1])
    _plot(axes[0], res, "flux_Wb")
    _ylabel(axes[0], "rotor flux", "flux_Wb")
    axes[0].legend(loc="best")
    errors = [("e_d0_Wb", {}), ("e_q0_Wb", {})]
    for col, style in errors:
        _plot(axes[1], res, col, **style)
    _ylabel(axes[1], "flux error", "e_d0_Wb")
    axes[1].legend(loc="best", fontsize=8)
    _zoom_panel(axes[2], res, errors, steady_start(res))
    _ylabel(axes[2], "flux error, zoom", "e_d0_Wb")
    _plot(axes[3], res, "R2_ohm")
    _plot(axes[3], res, "R2_hat_ohm", "--")
    _ylabel(axes[3], "rotor resistance", "R2_ohm")
    axes[3].legend(loc="best")
    _mark_switch_on(axes, res)
    return fig


def compensation_figure(res) -> Figure:
    """The paper's Figs. 5/6 layout: e_d0 (whole run, then zoomed on the steady state after
    the compensator switches on), the R2 estimate against the plant's R2, and the speeds."""
    s = res.signals
    fig, axes = _fig(
        4, f"{res.scenario.name}: rotor-resistance compensation", heights=[0.8, 1.3, 1, 1]
    )
    if demodulated_input(res.scenario.injection):
        shown = [("e_d0_Wb", {"lw": 0.6, "alpha": 0.6}), ("e_d0_demod_Wb", {"lw": 0.6})]
    else:
        shown = [("e_d0_Wb", {})]
    for col, style in shown:
        _plot(axes[0], res, col, **style)
    _ylabel(axes[0], "flux error", "e_d0_Wb")
    axes[0].set_title("whole run: the start-up transient sets the scale", fontsize=8, loc="left")
    _zoom_panel(axes[1], res, shown, steady_start(res))
    _ylabel(axes[1], "flux error, zoom", "e_d0_Wb")
    axes[1].legend(loc="upper right", fontsize=8)
    _plot(axes[2], res, "R2_ohm")
    _plot(axes[2], res, "R2_hat_ohm", "--")
    _ylabel(axes[2], "rotor resistance", "R2_ohm")
    axes[2].legend(loc="best")
    _plot(axes[3], res, "speed_rpm")
    _plot(axes[3], res, "speed_ref_rpm", "--")
    _plot(axes[3], res, "speed_est_rpm", ":")
    ref = s["speed_ref_rpm"][-1]
    axes[3].set_ylim(ref - 30 - 0.05 * abs(ref), ref + 30 + 0.05 * abs(ref))
    _ylabel(axes[3], "speed", "speed_rpm")
    axes[3].legend(loc="best")
    _mark_switch_on(axes, res)
    return fig


def save_figures(res, out_dir) -> list[Path]:
    """Write the run's PNG figures into the existing folder ``out_dir``; returns their paths.

    Each file by the output rule (:func:`imdrive._figure.save_png`): a path that is not a
    file to write (a missing folder, a device node, a FIFO in the figure's place) is refused
    with a :class:`~imdrive.errors.ConfigError` before that figure is written, and none is
    left half-written."""
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
    from imdrive._figure import save_png

    return [save_png(fig, out / name, dpi=110) for name, fig in figs.items()]


def _default_groups(res) -> list[list[str]]:
    cols = set(res.columns)
    groups = [[c for c in ("speed_rpm", "speed_ref_rpm", "speed_est_rpm") if c in cols]]
    groups.append([c for c in ("torque_Nm", "load_torque_Nm") if c in cols])
    groups.append([c for c in ("i_alpha_A", "i_beta_A") if c in cols])
    if "e_d0_Wb" in cols:
        groups.append(["e_d0_Wb"])
        groups.append(["R2_hat_ohm", "R2_ohm"])
    return [g for g in groups if g]


def result_figure(res, signals=None, t0: float = 0.0, t1=None) -> Figure:
    """Figure of a result: given columns one panel each, or the default groups (see
    :meth:`imdrive.run.result.SimulationResult.plot`); each column in its display unit
    (:func:`display_unit`: flux in mWb) and labelled with what it is."""
    signals = [current_name(s, stacklevel=3) for s in signals] if signals else None
    unknown = [s for s in (signals or []) if s not in res.signals]
    if unknown:
        raise KeyError(f"no such column(s) {unknown}; see res.columns")
    groups = [[s] for s in signals] if signals else _default_groups(res)
    w = res.window(t0, t1)
    fig, axes = _fig(len(groups), res.scenario.name)
    for ax, group in zip(axes, groups, strict=True):
        for name in group:
            k = display_unit(name)[1]
            ax.plot(w["time_s"], np.asarray(w[name]) * k, lw=0.9, label=signal_label(name, res))
        _ylabel(ax, QUANTITIES.get(unit_of(group[0]), "value"), group[0])
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (s)")
    return fig
