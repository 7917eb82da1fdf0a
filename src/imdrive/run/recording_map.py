"""Foreign recordings: which column is which signal, in what unit (``--map map.toml``).

A drive's data log or a scope capture names its columns its own way and stores currents in
mA, time in ms, the speed in rad/s, the voltages per phase or line to line. A mapping file
says, per signal, its column(s), unit and scale; :meth:`RecordingMap.convert` turns the
file's columns into the recording's own (:data:`~imdrive.run.recording.COLUMNS`, SI units):

.. code-block:: toml

    [time]
    column = "t_ms"
    unit = "ms"                      # s or ms

    [current]                        # phases (2 or 3 columns) or alpha-beta (2)
    columns = ["Ia", "Ib", "Ic"]
    frame = "phase"                  # phase or alpha-beta
    unit = "mA"                      # A or mA
    phase_order = "abc"              # which phase each column is (e.g. "acb")

    [voltage]
    columns = ["Vab", "Vbc", "Vca"]
    kind = "measured-phase-to-phase" # commanded-alpha-beta, commanded-phase,
                                     # measured-phase-to-neutral, measured-phase-to-phase
    unit = "V"

    [speed]                          # optional: the encoder
    column = "n"
    unit = "rpm"                     # rpm or rad/s (mechanical)

    [dc_link]                        # optional
    column = "Udc"

    [columns]                        # optional: any other recording column, by its own name
    id_ref_A = "idref"

Every signal takes ``scale`` (default 1), multiplied after the unit (a probe's ratio).

Three-phase quantities become space vectors by the amplitude-invariant Clarke transform,
``x_alpha = (2/3)(x_a - (x_b + x_c)/2)``, ``x_beta = (x_b - x_c)/sqrt(3)``; two phase
currents are completed by ``i_c = -i_a - i_b`` (a 3-wire machine). Line-to-line voltages are
converted to phase-to-neutral for a balanced 3-wire system (phase voltages summing to zero at
the star point): ``v_a = (v_ab - v_ca)/3``, ``v_b = (v_bc - v_ab)/3``, ``v_c = (v_ca - v_bc)/3``
(the alpha-beta vector, which has no zero sequence, is exact from line voltages whatever the
star point does). A voltage row ``k`` is taken as the voltage over ``[t_k, t_k + Ts)``: the
commanded one as commanded, a measured one as the logger's mean over the period.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from imdrive.errors import ConfigError

SQRT3 = math.sqrt(3.0)

#: unit -> factor to SI, per signal
UNITS = {
    "time": {"s": 1.0, "ms": 1e-3},
    "current": {"A": 1.0, "mA": 1e-3},
    "voltage": {"V": 1.0},
    "speed": {"rpm": 1.0, "rad/s": 30.0 / math.pi},  # to rpm (the recording's speed unit)
    "dc_link": {"V": 1.0},
}

#: voltage kinds -> (number of columns, what the columns are)
VOLTAGE_KINDS = {
    "commanded-alpha-beta": (2, "alpha, beta"),
    "commanded-phase": (3, "a, b, c"),
    "measured-phase-to-neutral": (3, "a, b, c"),
    "measured-phase-to-phase": (3, "ab, bc, ca"),
}

_KEYS = {
    "time": {"column", "unit", "scale"},
    "current": {"columns", "frame", "unit", "scale", "phase_order"},
    "voltage": {"columns", "kind", "unit", "scale", "phase_order"},
    "speed": {"column", "unit", "scale"},
    "dc_link": {"column", "unit", "scale"},
}


@dataclass
class Signal:
    """One mapped signal: its columns in the file, the factor to SI (unit times scale)."""

    columns: tuple[str, ...]
    factor: float
    unit: str
    kind: str = ""
    order: tuple[int, int, int] = (0, 1, 2)  # file column j is phase order[j]


@dataclass
class RecordingMap:
    """A mapping file read and checked (:func:`read_map`).

    Attributes
    ----------
    signals : dict
        ``time``, ``current``, ``voltage`` and, where given, ``speed``, ``dc_link``:
        :class:`Signal`.
    extra : dict
        Recording column name -> the file's column, taken as it is (SI).
    source : str
        Where it came from (for messages).
    """

    signals: dict
    extra: dict = field(default_factory=dict)
    source: str = "map"

    def file_columns(self) -> list[str]:
        """Every column of the file the mapping reads."""
        out = [c for s in self.signals.values() for c in s.columns]
        return out + list(self.extra.values())

    def describe(self) -> dict:
        """The mapping as ``summary.json`` records it."""
        d = {
            name: {"columns": list(s.columns), "unit": s.unit, "factor_to_SI": s.factor}
            | ({"kind": s.kind} if s.kind else {})
            for name, s in self.signals.items()
        }
        return d | ({"columns": dict(self.extra)} if self.extra else {})

    def column_of(self, name: str) -> str:
        """The file column(s) a recording column comes from (for messages)."""
        sig = {
            "time_s": "time",
            "i_alpha_meas_A": "current",
            "i_beta_meas_A": "current",
            "v_alpha_cmd_V": "voltage",
            "v_beta_cmd_V": "voltage",
            "speed_enc_rpm": "speed",
            "vdc_meas_V": "dc_link",
        }.get(name)
        if sig in self.signals:
            return ", ".join(self.signals[sig].columns)
        return self.extra.get(name, name)

    def convert(self, raw: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The recording's columns (SI) from the file's ``raw`` columns (one chunk).

        Parameters
        ----------
        raw : dict
            File column name -> float64 array (every column of :meth:`file_columns`).

        Returns
        -------
        dict
            ``time_s``, ``i_alpha_meas_A``, ``i_beta_meas_A``, ``v_alpha_cmd_V``,
            ``v_beta_cmd_V`` and, where mapped, ``speed_enc_rpm``, ``vdc_meas_V`` and the
            ``[columns]`` ones.
        """
        s = self.signals
        out = {"time_s": raw[s["time"].columns[0]] * s["time"].factor}
        cur = s["current"]
        if cur.kind == "alpha-beta":
            out["i_alpha_meas_A"] = raw[cur.columns[0]] * cur.factor
            out["i_beta_meas_A"] = raw[cur.columns[1]] * cur.factor
        else:
            x = [raw[c] * cur.factor for c in cur.columns]
            if len(x) == 2:  # a 3-wire machine: the third phase current closes the sum
                x.append(-x[0] - x[1])
            out["i_alpha_meas_A"], out["i_beta_meas_A"] = _clarke(_in_order(x, cur.order))
        vol = s["voltage"]
        x = [raw[c] * vol.factor for c in vol.columns]
        if vol.kind == "commanded-alpha-beta":
            out["v_alpha_cmd_V"], out["v_beta_cmd_V"] = x
        else:
            if vol.kind == "measured-phase-to-phase":
                x = phase_to_neutral(*x)
            out["v_alpha_cmd_V"], out["v_beta_cmd_V"] = _clarke(_in_order(x, vol.order))
        if "speed" in s:
            out["speed_enc_rpm"] = raw[s["speed"].columns[0]] * s["speed"].factor
        if "dc_link" in s:
            out["vdc_meas_V"] = raw[s["dc_link"].columns[0]] * s["dc_link"].factor
        for name, col in self.extra.items():
            out[name] = raw[col]
        return out


def phase_to_neutral(v_ab, v_bc, v_ca):
    """Phase-to-neutral voltages from line-to-line ones, for a balanced 3-wire system.

    ``v_a = (v_ab - v_ca)/3``, ``v_b = (v_bc - v_ab)/3``, ``v_c = (v_ca - v_bc)/3``: the
    unique solution of ``v_ab = v_a - v_b``, ``v_bc = v_b - v_c`` with ``v_a + v_b + v_c = 0``.

    Returns
    -------
    list of numpy.ndarray
        ``[v_a, v_b, v_c]``, V.
    """
    return [(v_ab - v_ca) / 3.0, (v_bc - v_ab) / 3.0, (v_ca - v_bc) / 3.0]


def _in_order(x: list, order: tuple[int, int, int]) -> list:
    """The file's phase columns ``x`` as phases a, b, c (``order[j]``: the phase of column j)."""
    out = [None, None, None]
    for j, ph in enumerate(order):
        out[ph] = x[j]
    return out


def _clarke(x: list) -> tuple[np.ndarray, np.ndarray]:
    """Amplitude-invariant Clarke transform of phases a, b, c."""
    a, b, c = x
    return (2.0 / 3.0) * (a - 0.5 * (b + c)), (b - c) / SQRT3


def _phase_order(where: str, text) -> tuple[int, int, int]:
    if not isinstance(text, str) or sorted(text.lower()) != ["a", "b", "c"]:
        raise ConfigError(
            f"{where}.phase_order", f"must name the phases a, b, c once each, got {text!r}"
        )
    return tuple("abc".index(ch) for ch in text.lower())


def _signal(where: str, name: str, table, optional: bool = False) -> Signal | None:
    if table is None:
        if optional:
            return None
        raise ConfigError(
            f"{where}: [{name}]", "missing: a mapping names time, current and voltage"
        )
    if not isinstance(table, dict):
        raise ConfigError(f"{where}: {name}", "must be a table ([" + name + "])")
    unknown = set(table) - _KEYS[name]
    if unknown:
        raise ConfigError(
            f"{where}: {name}.{sorted(unknown)[0]}",
            f"unknown key (known: {', '.join(sorted(_KEYS[name]))})",
        )
    units = UNITS[name]
    unit = table.get("unit", next(iter(units)))
    if unit not in units:
        raise ConfigError(
            f"{where}: {name}.unit", f"must be one of {', '.join(units)}, got {unit!r}"
        )
    scale = table.get("scale", 1.0)
    if (
        isinstance(scale, bool)
        or not isinstance(scale, int | float)
        or not math.isfinite(scale)
        or scale == 0
    ):
        raise ConfigError(
            f"{where}: {name}.scale", f"must be a finite non-zero number, got {scale!r}"
        )
    factor = units[unit] * float(scale)
    if "columns" in _KEYS[name]:
        cols = table.get("columns")
        kind, n_cols = _kind(where, name, table)
        if not isinstance(cols, list) or not all(isinstance(c, str) and c for c in cols):
            raise ConfigError(f"{where}: {name}.columns", "must be a list of column names")
        if len(cols) not in n_cols:
            raise ConfigError(
                f"{where}: {name}.columns",
                f"{kind} needs {' or '.join(map(str, n_cols))} columns, got {len(cols)}",
            )
        order = (0, 1, 2)
        if "phase_order" in table:
            if kind.endswith("alpha-beta"):
                raise ConfigError(f"{where}: {name}.phase_order", f"does not apply to {kind}")
            order = _phase_order(f"{where}: {name}", table["phase_order"])
        return Signal(tuple(cols), factor, unit, kind, order)
    col = table.get("column")
    if not isinstance(col, str) or not col:
        raise ConfigError(f"{where}: {name}.column", "must be a column name")
    return Signal((col,), factor, unit)


def _kind(where: str, name: str, table) -> tuple[str, tuple[int, ...]]:
    if name == "current":
        kind = table.get("frame", "phase")
        if kind not in ("phase", "alpha-beta"):
            raise ConfigError(
                f"{where}: current.frame", f"must be phase or alpha-beta, got {kind!r}"
            )
        return kind, ((2, 3) if kind == "phase" else (2,))
    kind = table.get("kind")
    if kind not in VOLTAGE_KINDS:
        raise ConfigError(
            f"{where}: voltage.kind", f"must be one of {', '.join(VOLTAGE_KINDS)}, got {kind!r}"
        )
    return kind, (VOLTAGE_KINDS[kind][0],)


def parse_map(data: dict, where: str = "map") -> RecordingMap:
    """A :class:`RecordingMap` from a mapping's tables (a parsed ``map.toml`` or a dict).

    Raises
    ------
    ConfigError
        One line naming the key and the rule: an unknown table or key, a unit not known, a
        wrong number of columns, a column named twice.
    """
    from imdrive.run.recording_columns import COLUMNS

    if not isinstance(data, dict):
        raise ConfigError(where, "must be a table of signals")
    known = set(_KEYS) | {"columns"}
    for key in data:
        if key not in known:
            raise ConfigError(
                f"{where}: {key}", f"unknown table (known: {', '.join(sorted(known))})"
            )
    signals = {}
    for name in _KEYS:
        sig = _signal(where, name, data.get(name), optional=name in ("speed", "dc_link"))
        if sig is not None:
            signals[name] = sig
    extra = data.get("columns", {})
    if not isinstance(extra, dict):
        raise ConfigError(f"{where}: columns", "must be a table of recording column = file column")
    for name, col in extra.items():
        if name not in COLUMNS or name in ("time_s", "i_alpha_meas_A", "i_beta_meas_A"):
            raise ConfigError(f"{where}: columns.{name}", "is not a context column of a recording")
        if not isinstance(col, str) or not col:
            raise ConfigError(f"{where}: columns.{name}", "must be a column name")
    seen: dict[str, str] = {}
    named = [
        (f"{n}.column{'s' if len(s.columns) > 1 else ''}", c)
        for n, s in signals.items()
        for c in s.columns
    ]
    named += [(f"columns.{n}", c) for n, c in extra.items()]
    for key, col in named:
        if col in seen:
            raise ConfigError(
                f"{where}: {key}",
                f"names the column {col!r} that {seen[col]} names too: each column is one signal",
            )
        seen[col] = key
    return RecordingMap(signals, dict(extra), where)


def read_map(path) -> RecordingMap:
    """Read a mapping file (``map.toml``) or take a mapping dict; see the module docstring."""
    import tomllib
    from pathlib import Path

    if isinstance(path, RecordingMap):
        return path
    if isinstance(path, dict):
        return parse_map(path)
    from imdrive.config.presets import MAX_TOML_BYTES
    from imdrive.config.user_files import lexists, path_form_problem, read_user_text

    problem = path_form_problem(path)
    if problem is not None:
        raise ConfigError("--map", problem)
    p = Path(path)
    if not lexists(p):
        raise ConfigError("--map", f"{p}: no such mapping file")
    text = read_user_text(p, "--map", MAX_TOML_BYTES, "mapping file")
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as exc:
        raise ConfigError(str(p), f"is not valid TOML ({exc})") from None
    return parse_map(data, str(p))
