"""The honest status of a run: whether its R̂2 and its speed can be relied on, and if not, why.

Every run (``summary.json`` ``"verdict"``, the batch and sweep tables' ``verdict`` and
``verdict_text`` columns, the console's closing line) carries a *verdict* built from its
metrics (:func:`imdrive.run.metrics.drive_metrics`) and its scenario:

``ok``
    the run completed, did not lose control, R̂2 ends within :data:`R2_TOLERANCE` of the
    plant's R2 (the simulator knows it) and the mean speed error over the final window is
    within :func:`imdrive.config.perunit.speed_tolerance_rpm`. When R̂2 is held at the end
    (not observable there) but still right, the text says so (``ok; R2 held since ...``).
``lost-control``, ``diverged``
    the first loss of control, the divergence (:mod:`imdrive.run.metrics`).
``frozen``
    the compensator is held at the end and R̂2 never moved from its starting value: it was
    never estimated in this run.
``held``
    the compensator estimated, then held R̂2 from ``R2_held_since_s`` to the end.
``R2-off``
    R̂2 ends more than :data:`R2_TOLERANCE` from R2 while it was being estimated (or with no
    compensator); the text says when R̂2 ended on one of its clamps (``compensator.R2_min_*``,
    ``R2_max_*``), which then kept it from R2.
``R2-unsettled``
    R̂2 ends within the tolerance but was outside it within the final window
    (``R2_error_window_pct``): it swings, and its end value is a phase of the swing.
``speed-error``
    the mean speed error over the final window exceeds the tolerance, or the speed swings
    over a settled final window by more than :data:`SPEED_SWING_TOLERANCES` times it, peak to
    peak (``speed_ripple_rpm``): a drive in a limit cycle can hold its mean.
``not-run``
    the scenario could not be built (the batch's ``status`` -1).

A run whose standstill R1 identification (``mras.R1_standstill``) could not identify
(``R1_id_status`` 2: the speed reference left zero before the measured flux build-up was
over, or the drive was not still) says so in ``verdict_text`` whatever its verdict
(:data:`R1_NOT_IDENTIFIED`): the MRAS then ran on R̂1 as it was given. A two-level test
(``mras.R1_standstill_levels = 2``) that identified its first level only (``R1_id_status`` 3:
the second level's window was too short) says so too (:data:`R1_ONE_LEVEL`): R̂1 then holds
the inverter's residual voltage over the current, as the one-level test's does.

A sensorless run that failed (lost control or diverged, its compensator did not track R2, or
it missed its speed with R2_hat right) and whose steady state at the end runs within
:data:`LOW_FREQUENCY_PU` of the rated frequency of zero stator frequency says so last in
``verdict_text`` (:func:`low_frequency_note`): at 0 Hz the speed and R2 are not observable
from the fundamental-frequency signals, and beside it the MRAS loses its stability margin.

The failures are listed in time order (a loss of control before the divergence it led to, a
hold before the R̂2 error it left at the end) and the verdict is the first; ``verdict_text``
names every one. Why R̂2 was held comes from the compensator's gating mask (the log column
``comp_frozen_flags``, :mod:`imdrive.kernels.compensator`), grouped as a drive engineer reads
it (:data:`HELD_CAUSES`): the voltage limit (the injection backed off for headroom or in field
weakening, or the voltage at the inverter's limit), the stator frequency band (the stator
frequency near the injection's, where the injected signal is not detectable), the injection's
start (the model-based law waits for the flux response to settle), a window in which R2 is
not observable (the detection's modelled response to an R2 error is not positive), or a gated
transient (a speed or load change, and the settling after it).

Speed accuracy is also given in per-unit of the machine's rated slip speed
(``speed_error_pu_slip``): the slip error a wrong R̂2 causes scales with it, so the same
number means the same on every machine of the library.
"""

from __future__ import annotations

import math

from imdrive.config.perunit import rated_slip_rpm, resolve, speed_tolerance_rpm
from imdrive.config.sequence import (
    DEFAULT_WINDOW_S,
    MIN_SETTLED_SHARE,
    sequence,
    settled_at_s,
)
from imdrive.kernels.batch import CONVERGENCE_BAND

#: R̂2 within this fraction of the plant's R2 at the end: the convergence band of the metrics
#: (``convergence_time_s``), the envelope's goal on the ideal drive.
R2_TOLERANCE = CONVERGENCE_BAND

#: Gating bit (``comp_frozen``) -> (group, what it means), the groups in the order they are
#: named (the voltage limit first: it outlasts the transients it causes).
HELD_CAUSES = {
    32: ("voltage limit", "injection backed off for voltage headroom / field weakening"),
    4: ("voltage limit", "voltage at the gating's limit"),
    8: ("stator frequency band", "stator frequency near the injection frequency"),
    64: ("injection start", "the injection started: the flux response to it settles"),
    1: ("gated transient", "speed reference or speed error moving"),
    2: ("gated transient", "load step"),
    16: ("gated transient", "settling after a gated event"),
    128: ("not observable", "the detection's modelled response to R2 has no sign here"),
}

#: Columns the status adds to a metrics row (batch, sweep, ``drive_metrics``).
STATUS_COLUMNS = (
    "speed_error_pu_slip",
    "speed_tolerance_rpm",
    "verdict",
    "verdict_ok",
    "verdict_text",
    "verdict_at_s",
)

#: The note a run's ``verdict_text`` carries when its standstill R1 identification could not
#: identify (``R1_id_status`` 2).
R1_NOT_IDENTIFIED = (
    "standstill R1 not identified (its last standstill run ended before the measured flux "
    "build-up was over, or the drive was not still): R1_hat as it was"
)

#: The note when a two-level standstill test identified its first level only (status 3).
R1_ONE_LEVEL = (
    "standstill R1 identified at one current level only (the second level's window was too "
    "short): R1_hat holds the inverter's residual voltage over the current"
)

#: A failed sensorless run whose final steady state runs below this fraction of the machine's
#: rated frequency says so (:func:`low_frequency_note`): 1.2 Hz at 60 Hz, 1 Hz at 50 Hz.
#: Measured (docs/machine-envelope.md, regenerating the rated torque on four machines): from
#: +2 Hz every run converged, the failures were at +1 Hz and below.
LOW_FREQUENCY_PU = 0.02

#: A settled final window whose speed swings by more than this many speed tolerances peak to
#: peak (``speed_ripple_rpm``) is a speed error whatever its mean: 17 rpm on Table IV (22 % of
#: its rated slip). Measured: Table IV's ``sensorless`` with ``control.speed_kp = 0.1`` (a
#: sixteenth of the derived gain, an underdamped speed loop) swings 190 rpm (110 times) with a
#: mean error of -1.5 rpm, and read ``ok``; Krause 50 hp's observer drive from R2_hat = 0.8 R2
#: regenerating the rated torque at 140 rpm, in a limit cycle at 2.25 Hz, 37 rpm (21 times).
#: Every ``ok`` run of the machine envelope and the zero-frequency study swings at most 0.28
#: times the tolerance, of the packaged presets 1.8 times (``paper-fig6-realistic``), of the
#: realistic envelope (switching, sensors' noise, injection) 2.4 times.
SPEED_SWING_TOLERANCES = 10.0


def _r2_exact(sc, row: dict) -> bool:
    """Whether the run ends with R2_hat within :data:`R2_TOLERANCE` of R2 (its speed error,
    if any, then not the detuning's)."""
    r2_hat, r2 = row.get("R2_hat_final_ohm", math.nan), row.get("R2_final_ohm", math.nan)
    r2 = float(r2) if _finite(r2) and float(r2) > 0.0 else sc.machine.R2_ohm
    return _finite(r2_hat) and abs(float(r2_hat) / r2 - 1.0) <= R2_TOLERANCE


def low_frequency_note(sc, row: dict, lost: bool) -> str:
    """``"; near zero stator frequency ..."`` for a sensorless run whose steady state at the
    end runs within :data:`LOW_FREQUENCY_PU` of the rated frequency of zero, else ``""``;
    ``lost``: the run lost control or diverged.

    The steady state is the field-oriented one (:func:`imdrive.analysis.foc_operating_point`)
    at the final speed reference, the final load (its profile, viscous and fan terms at that
    speed) and the final ``R2_hat/R2``; only for a run that lost control or diverged, whose
    compensator failed, or whose R2_hat is right (an R2 left detuned explains its own error;
    with R2_hat right, a speed error near 0 Hz is the estimator's: the adaptive observer 104
    rpm off at 70 rpm regenerating the rated torque on the realistic drive, -0.3 Hz,
    docs/estimators.md). At ``f_s = 0``
    neither the speed nor R2 can be told from the fundamental-frequency voltages and currents
    (Holtz, "Sensorless control of induction motor drives", Proc. IEEE 90(8), 2002), and
    beside it the MRAS loses its stability where the adaptive full-order observer with its
    regeneration gain holds (docs/machine-envelope.md, the zero-frequency study): the note
    says why such a run failed and what held there; it does not change its verdict.
    """
    if sc.control.speed_feedback == "measured" or sc.drive.mode != "vector":
        return ""
    if not (lost or sc.compensator.enabled or _r2_exact(sc, row)):
        return ""  # a detuned drive's error is the detuning's
    from imdrive.analysis.foc import foc_operating_point

    try:
        seq = sequence(sc)
        n = seq.speed_ref_rpm.final
        w = n * math.pi / 30.0
        load = seq.load_Nm.final + sc.load.viscous_Nms * w + sc.load.fan_Nms2 * w * abs(w)
        r2_hat = row.get("R2_hat_final_ohm", math.nan)
        r2 = row.get("R2_final_ohm", math.nan)
        r2_hat = float(r2_hat) if _finite(r2_hat) else resolve(sc).R2_hat
        r2 = float(r2) if _finite(r2) and float(r2) > 0.0 else sc.machine.R2_ohm
        f_s = foc_operating_point(sc.machine, n, load, r2_hat / r2).f_Hz
    except (ArithmeticError, ValueError, RuntimeError):  # no steady state to speak of
        return ""
    if not math.isfinite(f_s) or abs(f_s) > LOW_FREQUENCY_PU * sc.machine.rated_frequency_Hz:
        return ""
    other = (
        ""
        if sc.control.speed_feedback == "afo"
        else ' (control.speed_feedback = "afo" held these points in docs/machine-envelope.md)'
    )
    return (
        f"; near zero stator frequency (steady state {f_s:+.2f} Hz, within "
        f"{100 * LOW_FREQUENCY_PU:.0f} % of the rated {sc.machine.rated_frequency_Hz:g} Hz): "
        "at 0 Hz the speed and R2 cannot be told from the fundamental-frequency signals, and "
        f"near it only an estimator whose gain is designed for regeneration holds{other}"
    )


#: The verdicts that end a run's meaning: the verdict whenever they occur, before the
#: first cause otherwise.
FATAL = ("lost-control", "diverged")

VERDICTS = (
    "ok",
    "lost-control",
    "diverged",
    "frozen",
    "held",
    "R2-off",
    "R2-unsettled",
    "speed-error",
    "not-run",
)


def r2_worst_pct(end_pct, window_pct=math.nan):
    """``|R̂2 - R2| / R2``, %: the larger of the error at the end and the final window's worst
    (``R2_error_pct``, ``R2_error_window_pct``; a missing or NaN window reads the end alone:
    CSVs from before the window column). Scalars or arrays (``numpy.fmax``)."""
    import numpy as np

    return np.fmax(np.abs(end_pct), np.abs(window_pct))


def held_reasons(mask) -> list[str]:
    """The groups of a gating mask, in the order of :data:`HELD_CAUSES` (unknown bits named).

    Parameters
    ----------
    mask : int or float
        OR of ``comp_frozen`` values (0 or NaN: none).

    Returns
    -------
    list of str
        E.g. ``["voltage limit"]``; a settling bit alone (16) reads ``"gated transient"``.
    """
    if mask is None or (isinstance(mask, float) and math.isnan(mask)):
        return []
    m = int(mask)
    out: list[str] = []
    for bit, (group, _) in HELD_CAUSES.items():
        if m & bit and group not in out:
            out.append(group)
    rest = m & ~sum(HELD_CAUSES)
    b = 1
    while rest:
        if rest & b:
            out.append(f"gating bit {b}")
            rest &= ~b
        b <<= 1
    # a settling hold (16) after a voltage or band event belongs to that event
    if "gated transient" in out and len(out) > 1 and not m & 3:
        out.remove("gated transient")
    return out


def _finite(x) -> bool:
    try:
        return x is not None and math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


def _at_clamp(sc, r2_end) -> str:
    """`` (at its upper clamp ...)`` when R̂2 ended on a clamp of the compensator, else ""."""
    if not _finite(r2_end):
        return ""
    r = resolve(sc)
    for bound, name, key in ((r.R2_max, "upper", "max"), (r.R2_min, "lower", "min")):
        if abs(float(r2_end) - bound) <= 1e-9 * bound:
            return (
                f" (at its {name} clamp, {bound / r.R2_hat:.3g} R2_hat(0): "
                f"compensator.R2_{key}_ratio / R2_{key}_ohm)"
            )
    return ""


def sequence_notes(sc, row: dict, t_end: float) -> str:
    """What the drive's sequencing did, for ``verdict_text`` (``""`` when nothing): the
    premagnetisation's delay of the duty cycle, the ramps followed at the torque limit
    (:mod:`imdrive.config.sequence`), how long the speed followed its reference at the torque
    limit out of the loss-of-control band (``torque_limited_s``, when at least a tenth of
    ``simulation.lost_control_s``), and a final window that
    begins before the last transient had settled (:func:`imdrive.config.sequence.settled_at_s`,
    ``window_s`` of ``row``, default 0.5 s)."""
    if sc.drive.mode != "vector":
        return ""
    seq = sequence(sc)
    out = ""
    # the standstill R1 test extends the premagnetisation until its window (the kernel's
    # t_hold, config/sequence.py): the note says so rather than a length it cannot know
    test = sc.mras.R1_standstill
    if seq.delay_s > 0.0:
        out += (
            f"; premagnetised for {'at least ' if test else ''}{seq.premagnetise_s:.3g} s "
            f"(control.premagnetise_T2 = {sc.control.premagnetise_T2:g} rotor time constants"
            f"{', and until the standstill R1 test had its window' if test else ''}): the "
            f"profiles start {'at least ' if test else ''}{seq.delay_s:.3g} s later"
        )
    out += "".join(f"; {r.text()}" for r in seq.limited)
    limited = row.get("torque_limited_s", math.nan)
    if _finite(limited) and float(limited) >= 0.1 * sc.simulation.lost_control_s:
        out += (
            f"; the speed followed its reference at the torque limit for {float(limited):.3g} s "
            "(not a loss of control)"
        )
    window = row.get("window_s", DEFAULT_WINDOW_S)
    settled = settled_at_s(sc)
    if t_end - settled < MIN_SETTLED_SHARE * min(window, t_end):
        out += (
            f"; not settled: the last change of the speed reference or load settles at about "
            f"t = {settled:.3g} s, the final window reads t = {max(t_end - window, 0.0):.3g} "
            f"to {t_end:.3g} s (lengthen simulation.t_end_s)"
        )
    return out


def _speed_events(sc, row: dict, out: dict, tol_rpm: float, t_end: float) -> list:
    """The speed's failures of a completed field-oriented run, ``(time, code, text)``: the
    mean error over the final window beyond ``tol_rpm``, and a swing beyond
    :data:`SPEED_SWING_TOLERANCES` of it over a settled final window."""
    events = []
    err = row.get("speed_error_rpm", math.nan)
    if _finite(err) and abs(float(err)) > tol_rpm:
        events.append(
            (
                t_end,
                "speed-error",
                f"speed error {float(err):+.3g} rpm > tol {tol_rpm:.3g} rpm "
                f"({out['speed_error_pu_slip']:+.3g} x rated slip)",
            )
        )
    swing = row.get("speed_ripple_rpm", math.nan)
    window = row.get("window_s", DEFAULT_WINDOW_S)
    settled = t_end - settled_at_s(sc) >= min(window, t_end)
    if settled and _finite(swing) and float(swing) > SPEED_SWING_TOLERANCES * tol_rpm:
        events.append(
            (
                t_end,
                "speed-error",
                f"speed swings {float(swing):.3g} rpm peak to peak over the final window "
                f"(> {SPEED_SWING_TOLERANCES:g} x tol)",
            )
        )
    return events


def verdict(sc, row: dict) -> dict:
    """The status columns of one run (module docstring).

    Parameters
    ----------
    sc : Scenario
        The scenario as run.
    row : dict
        Its metrics: ``status``, ``diverged_at_s``, ``lost_control_at_s``, ``R2_error_pct``,
        ``speed_error_rpm``, ``R2_hat_final_ohm``, ``R2_held_since_s``,
        ``R2_held_end_causes``, ``simulated_s``, ``R1_id_status`` and ``R2_error_window_pct``
        (optional).

    Returns
    -------
    dict
        :data:`STATUS_COLUMNS`: the speed error in per-unit of the rated slip speed, the
        tolerance (rpm), the verdict (one of :data:`VERDICTS`), whether it is ``ok`` (a
        boolean column, for the heatmaps' shares), its text and the time of its cause, s
        (NaN for ``ok``). The verdict is the first cause in time, or the loss of control
        (divergence) whenever there is one.
    """
    tol_rpm = speed_tolerance_rpm(sc)
    slip = rated_slip_rpm(sc)
    err = row.get("speed_error_rpm", math.nan)
    out = {
        "speed_error_pu_slip": float(err) / slip if _finite(err) and slip > 0 else math.nan,
        "speed_tolerance_rpm": tol_rpm,
    }
    status = row.get("status", 0)
    if isinstance(status, str):  # summary.json's text ("ok" or what diverged)
        status = 0 if status == "ok" else 1
    status = int(status)
    if status < 0:
        out["verdict"] = "not-run"
        out["verdict_ok"] = False
        out["verdict_text"] = f"not run: {row.get('error') or 'the scenario could not be built'}"
        out["verdict_at_s"] = math.nan
        return out
    t_end = float(row.get("simulated_s", sc.simulation.t_end_s))
    events: list[tuple[float, str, str]] = []  # (time, code, text)
    if _finite(row.get("lost_control_at_s")):
        t = float(row["lost_control_at_s"])
        events.append((t, "lost-control", f"lost control at t = {t:.3g} s"))
    if status != 0:
        t = float(row.get("diverged_at_s", t_end))
        events.append((t, "diverged", f"diverged at t = {t:.3g} s"))
    vector = sc.drive.mode == "vector"
    comp = sc.compensator
    held_note = None
    if vector and comp.enabled and _finite(row.get("R2_held_since_s")):
        t = float(row["R2_held_since_s"])
        why = ", ".join(held_reasons(row.get("R2_held_end_causes"))) or "gating"
        r2_0 = resolve(sc).R2_hat
        r2_end = row.get("R2_hat_final_ohm", math.nan)
        if _finite(r2_end) and abs(float(r2_end) - r2_0) <= 1e-12 * r2_0:
            code = "frozen"
            text = f"compensator frozen from t = {t:.3g} s ({why}): R2 never estimated"
        else:
            code, text = "held", f"R2 held since t = {t:.3g} s ({why})"
        held_note = (t, code, text)
    r2_err = row.get("R2_error_pct", math.nan)
    r2_bad = vector and _finite(r2_err) and abs(float(r2_err)) > 100.0 * R2_TOLERANCE
    if r2_bad:
        if held_note is not None:
            events.append(held_note)
        what = "" if comp.enabled else " (compensator off)"
        if comp.enabled:
            what = _at_clamp(sc, row.get("R2_hat_final_ohm"))
        events.append((t_end, "R2-off", f"R2_hat off by {float(r2_err):+.3g} %{what}"))
    r2_win = row.get("R2_error_window_pct", math.nan)
    if vector and not r2_bad and _finite(r2_win) and abs(float(r2_win)) > 100.0 * R2_TOLERANCE:
        if held_note is not None:
            events.append(held_note)
        events.append(
            (
                t_end,
                "R2-unsettled",
                f"R2_hat not settled: {float(r2_win):+.3g} % off within the final window "
                f"(ends {float(r2_err):+.3g} %)",
            )
        )
    if vector and status == 0:
        events += _speed_events(sc, row, out, tol_rpm, t_end)
    events.sort(key=lambda e: e[0])
    r1_note = {2: f"; {R1_NOT_IDENTIFIED}", 3: f"; {R1_ONE_LEVEL}"}.get(row.get("R1_id_status"), "")
    r1_note += sequence_notes(sc, row, t_end)
    if events:
        # the first cause, but a loss of control or a divergence outranks what came before it
        # (an R2_hat held, then control lost, is a lost run: its verdict said "held")
        fatal = [e for e in events if e[1] in FATAL]
        first = fatal[0] if fatal else events[0]
        out["verdict"] = first[1]
        out["verdict_ok"] = False
        out["verdict_text"] = "; ".join(e[2] for e in events) + r1_note
        out["verdict_text"] += low_frequency_note(sc, row, bool(fatal))
        out["verdict_at_s"] = first[0]
        return out
    out["verdict"] = "ok"
    out["verdict_ok"] = True
    out["verdict_at_s"] = math.nan
    held = f"; {held_note[2]}, still within tolerance" if held_note else ""
    out["verdict_text"] = "ok" + held + r1_note
    return out


#: R̂2 held for more than this share of the time (%) since the compensator started: the
#: console and ``summary.json`` say how long and why (issue 38: a hold the user cannot see is
#: an R̂2 they cannot trust).
HELD_NOTE_PCT = 10.0


def held_note(held_pct: float, shares: dict[str, float] | None) -> str | None:
    """``"R2_hat held 23 % of the time since the compensator started: stator frequency band
    18 %, gated transient 5 %"`` when ``held_pct`` exceeds :data:`HELD_NOTE_PCT`, else None.

    Parameters
    ----------
    held_pct : float
        ``R2_held_pct`` of the run, %.
    shares : dict of str to float, optional
        :func:`imdrive.run.metrics.held_shares` of the run, % by cause.
    """
    if not _finite(held_pct) or held_pct <= HELD_NOTE_PCT:
        return None
    why = ", ".join(f"{g} {p:.0f} %" for g, p in (shares or {}).items())
    return f"R2_hat held {held_pct:.0f} % of the time since the compensator started" + (
        f": {why}" if why else ""
    )


def r1_note(g: float | None) -> str | None:
    """The sentence a run's status carries when R2_hat at its final operating point depends
    on R1_hat more than the R2 tolerance allows: ``g`` times
    :data:`~imdrive.analysis.observability.R1_UNCERTAINTY` above :data:`R2_TOLERANCE`
    (``g``: :func:`imdrive.run.metrics.r1_sensitivity`). None otherwise."""
    if g is None:  # before the import: the analysis package loads scipy.optimize (0.3 s)
        return None
    from imdrive.analysis.observability import R1_UNCERTAINTY

    if not g * R1_UNCERTAINTY > R2_TOLERANCE:
        return None
    d1 = 100 * R1_UNCERTAINTY
    if math.isinf(g):
        return "R2 not observable here: at zero stator frequency R2_hat follows R1_hat's error"
    return (
        f"R2 weakly observable here: at this low stator frequency a {d1:g} % error of R1_hat "
        f"moves R2_hat by about {g * d1:.1f} %, beyond the {100 * R2_TOLERANCE:g} % tolerance"
    )


def run_status(m: dict, shares: dict[str, float] | None = None, g_R1: float | None = None) -> dict:
    """``summary.json``'s ``"verdict"`` from a run's metrics (:func:`drive_metrics`): the
    status columns, the R̂2 tolerance, how long and why R̂2 was held (the gating masks as
    their groups, :func:`held_reasons`; None without a compensator), and ``R2_observable``:
    ``"estimated at the end"``, or ``"not observable here: held since t = ... s (reason)"``
    (None without a compensator).

    Parameters
    ----------
    m : dict
        :func:`imdrive.run.metrics.drive_metrics` of the run.
    shares : dict of str to float, optional
        :func:`imdrive.run.metrics.held_shares` of the run: ``R2_held_by_cause_pct``, and the
        ``R2_held_note`` (:func:`held_note`) names them.
    g_R1 : float, optional
        :func:`imdrive.run.metrics.r1_sensitivity` of the run: ``R2_R1_sensitivity``, and
        the ``R2_R1_note`` (:func:`r1_note`) when it exceeds the tolerance.

    Returns
    -------
    dict
        JSON-ready values.
    """
    got = {k: m[k] for k in (*STATUS_COLUMNS, "R2_held_pct", "R2_held_since_s")}
    for key in ("R2_held_causes", "R2_held_end_causes"):
        got[key] = held_reasons(m[key]) if _finite(m[key]) else None
    got["R2_held_by_cause_pct"] = shares if _finite(m["R2_held_pct"]) else None
    got["R2_held_note"] = held_note(m["R2_held_pct"], shares)
    got["R2_tolerance_pct"] = 100.0 * R2_TOLERANCE
    if g_R1 is not None and math.isnan(g_R1):
        g_R1 = None  # no flux to read it from
    got["R2_R1_sensitivity"] = g_R1 if g_R1 is None or math.isfinite(g_R1) else "inf"
    got["R2_R1_note"] = r1_note(g_R1)
    since = m["R2_held_since_s"]
    if not _finite(m["R2_held_pct"]):
        got["R2_observable"] = None  # no compensator: R2_hat is not estimated at all
    elif _finite(since):
        why = ", ".join(got["R2_held_end_causes"] or []) or "gating"
        got["R2_observable"] = f"not observable here: held since t = {since:.3g} s ({why})"
    else:
        got["R2_observable"] = "estimated at the end"
    return got


def verdict_counts(df) -> str:
    """``"ok in 812 of 1920 (frozen 300, R2-off 12, ...)"`` for a batch or sweep table, or ""
    for a table without a ``verdict`` column (a store written before the status existed)."""
    if "verdict" not in df:
        return ""
    counts = df["verdict"].value_counts()
    n_ok = int(counts.get("ok", 0))
    rest = ", ".join(f"{c} {int(counts[c])}" for c in VERDICTS if c != "ok" and c in counts)
    return f"ok in {n_ok} of {len(df)}" + (f" ({rest})" if rest else "")
