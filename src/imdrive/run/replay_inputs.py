"""What a replay takes in: the scenario, the estimators, and the recording's rules that
depend on the scenario (:mod:`imdrive.run.replay`).

The recording's own rules (columns, time, finite values) are checked as it is read
(:mod:`imdrive.run.recording_read`); the ones here need the drive: its sample period against
the controller's (:func:`decimation`), its magnitudes against the machine's rated ones
(:func:`check_units`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from imdrive.errors import ConfigError

#: a recorded magnitude above this many times the machine's rated one is a unit error
UNIT_LIMIT = 20.0


def _scenario(rec, scenario):
    """The scenario to replay with: the one given, or the recording's own."""
    from imdrive.config.scenario import Scenario

    if scenario is None:
        data = rec.meta.get("scenario")
        if not data:
            raise ConfigError(
                "--scenario",
                f"{rec.path} has no recording.toml naming its scenario: give the drive's "
                "scenario (its machine and controller model set the estimators' records)",
            )
        import copy

        from imdrive.config.plugins import resolve_plugin_paths

        # its plug-in modules are named relative to the recording's folder (portable)
        data = copy.deepcopy(data)
        resolve_plugin_paths(data, Path(rec.path).parent)
        return Scenario.from_dict(data)
    if isinstance(scenario, Scenario):
        return scenario
    return Scenario.read(str(scenario))


#: ``replay(r2_law=...)``: run the scenario's R2 law where it can, always (or refuse), never
R2_LAW_CHOICES = ("auto", "on", "off")


def law_replayed(r2_law: str, sc, comp, columns) -> tuple[bool, str]:
    """Whether the replay runs the scenario's R2 law, and a line saying what ``R2_hat`` is.

    Parameters
    ----------
    r2_law : {"auto", "on", "off"}
        ``"auto"``: where the scenario's compensator is on and the recording carries its
        excitation (``i_inj_A`` where the law injects); ``"on"``: refused where it cannot;
        ``"off"``: ``R2_hat`` as the recorded controller wrote it.
    sc : Scenario
    comp : numpy.ndarray
        The compensator's params records of the scenario's drive (``inj_amp``).
    columns : collection of str
        The recording's columns.

    Raises
    ------
    ConfigError
        ``--r2-law`` not a choice; ``"on"`` where the law cannot run.
    """
    if r2_law not in R2_LAW_CHOICES:
        raise ConfigError("--r2-law", f"must be one of {', '.join(R2_LAW_CHOICES)}, got {r2_law!r}")
    recorded = "R2_hat as the recorded controller wrote it, or the estimator's own"
    if r2_law == "off":
        return False, f"not replayed (--r2-law off): {recorded}"
    why = None
    if not sc.compensator.enabled:
        why = "the scenario runs no R2 law (compensator.enabled = false)"
    elif float(comp[0]["inj_amp"]) != 0.0 and "i_inj_A" not in columns:
        why = "the recording lacks its excitation: the injected current i_inj_A"
    if why is not None:
        if r2_law == "on":
            raise ConfigError("--r2-law", f"cannot replay the R2 law: {why}")
        return False, f"not replayed: {why}; {recorded}"
    law = sc.compensator.step_law
    excitation = "the injection" if float(comp[0]["inj_amp"]) != 0.0 else "the fundamental"
    return True, f"{law!r} law on each estimator's flux error, excited by {excitation}"


def _scenario_of(sc, name: str):
    """The scenario with ``name`` as its estimator: ``sc`` itself for the run's own (its records
    exactly as the run's); another with the compensator off where the scenario refuses the
    estimator with it (its R2 law then does not run on that estimator, which says so in its
    summary's ``R2_law``)."""
    own = sc.control.speed_feedback
    if own == name or (own == "measured" and name == "mras"):
        return sc
    try:
        return sc.with_overrides({"control.speed_feedback": name})
    except ConfigError:
        return sc.with_overrides({"control.speed_feedback": name, "compensator.enabled": False})


def _estimator_names(estimators, rec) -> list[str]:
    from imdrive.run.estimators import estimator_names

    if estimators is None:
        estimators = [rec.meta.get("recording", {}).get("estimator", "mras")]
    if isinstance(estimators, str):
        estimators = [e.strip() for e in estimators.split(",") if e.strip()]
    names = list(dict.fromkeys("mras" if e == "measured" else e for e in estimators))
    known = [n for n in estimator_names() if n != "measured"]
    for n in names:
        if n not in known:
            raise ConfigError("--estimators", f"no estimator {n!r} (known: {', '.join(known)})")
    if not names:
        raise ConfigError("--estimators", f"name at least one of {', '.join(known)}")
    return names


def decimation(rec, Ts: float) -> int:
    """How many recorded rows make one control period: 1 where the recording is sampled at
    the controller's rate (within 1 %), the integer ratio where it is faster.

    Raises
    ------
    ConfigError
        A recording slower than the controller, or faster by a ratio that is not an integer
        (within 1 %).
    """
    where = f"{rec.path}: column {rec.column_of('time_s')}"
    p = rec.period_s
    if p > 1.01 * Ts:
        raise ConfigError(
            where,
            f"sample period {p:.6g} s is longer than the controller's Ts {Ts:.6g} s "
            "(simulation.Ts_s): a recording slower than the controller cannot be replayed "
            "(the estimators integrate over one control period; --controller-period file "
            "replays at the recording's period)",
        )
    q = round(Ts / p)
    if abs(q * p - Ts) > 0.01 * Ts:
        raise ConfigError(
            where,
            f"sample period {p:.6g} s does not divide the controller's Ts {Ts:.6g} s "
            f"(ratio {Ts / p:.4g}): only an integer ratio can be decimated to the controller's "
            "period (give --controller-period file to replay at the recording's own period)",
        )
    return int(q)


def _limits(sc) -> dict[str, tuple[float, str]]:
    """Recording column -> (largest plausible magnitude, the rule), from the machine's rated
    point: :data:`UNIT_LIMIT` times the rated peak current, phase voltage, speed."""
    from imdrive.config.rated import rated_point

    try:
        rp = rated_point(sc.machine)
    except ConfigError:  # a machine without a rated point: no check
        return {}
    i_pk = rp.current_peak_A
    v_pk = rp.voltage_V * math.sqrt(2.0 / 3.0)
    n_r = max(rp.synchronous_speed_rpm, abs(rp.speed_rpm))
    x = UNIT_LIMIT
    return {
        "i": (x * i_pk, f"the machine's rated peak current {i_pk:.4g} A", "A", "A or mA"),
        "v": (x * v_pk, f"its rated peak phase voltage {v_pk:.4g} V", "V", "V"),
        "n": (x * n_r, f"its synchronous speed {n_r:.4g} rpm", "rpm", "rpm or rad/s"),
    }


def check_units(rec, cols: dict, k0: int, limits: dict) -> None:
    """Refuse a chunk whose current, voltage or speed is more than :data:`UNIT_LIMIT` times
    the machine's rated one (a unit or scale that contradicts the scenario): one line
    naming the file's column, the row and the rule."""
    checks = [
        ("i", ("i_alpha_meas_A", "i_beta_meas_A")),
        ("v", ("v_alpha_cmd_V", "v_beta_cmd_V")),
    ]
    if "speed_enc_rpm" in cols:
        checks.append(("n", ("speed_enc_rpm",)))
    for key, names in checks:
        if key not in limits or len(cols[names[0]]) == 0:
            continue
        lim, rated, unit, units = limits[key]
        name = names[0]
        square = sum(cols[c] * cols[c] for c in names)  # no hypot: a square is cheaper
        if not np.max(square) > lim * lim:
            continue
        mag = np.sqrt(square)
        bad = np.flatnonzero(mag > lim)
        if bad.size:
            k = int(bad[0])
            x = float(mag[k])
            raise ConfigError(
                f"{rec.path}: column {rec.column_of(name)} row {k0 + k}",
                f"magnitude {x:.4g} {unit} is {x / (lim / UNIT_LIMIT):.3g} times {rated}: "
                f"more than {UNIT_LIMIT:g} times contradicts the scenario (check the unit, "
                f"{units}, and the scale, or the scenario's machine)",
            )
