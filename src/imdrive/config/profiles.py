"""Time profiles: speed references, load torques, resistance changes, ...

Every profile is a piecewise-linear function of time given by breakpoints ``(t_i, v_i)`` with
non-decreasing times. Two breakpoints at the same time make a step (the function is continuous
from the right: at the step time it already has the new value). Before the first breakpoint the
function holds the first value, after the last one the last value.

In a scenario file a profile is written either as a number (constant), as explicit points::

    speed_ref_rpm = { points = [[0, 0], [0.2, 1000], [1.0, 1000], [1.0, 500]] }

or as an initial value followed by changes, each a step (no ``over``) or a ramp lasting ``over``
seconds::

    load_Nm = { initial = 0, changes = [{ at = 0.5, to = 12 }, { at = 2, to = 6, over = 1 }] }
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from pydantic_core import core_schema

from imdrive.errors import ConfigError, check_number

_NUMBER = {"type": "number"}

#: JSON Schema of the scenario-file forms of a profile (editors validate TOML with it).
PROFILE_JSON_SCHEMA = {
    "title": "Profile",
    "description": (
        "A piecewise-linear function of time: a number (constant), explicit points "
        "[[t, value], ...] (two points at the same time make a step), or an initial value "
        "and changes {at, to[, over]} (a step without 'over', else a ramp lasting 'over' s)."
    ),
    "anyOf": [
        _NUMBER,
        {
            "type": "object",
            "properties": {
                "points": {
                    "type": "array",
                    "minItems": 1,
                    "items": {
                        "type": "array",
                        "prefixItems": [{"type": "number", "minimum": 0}, _NUMBER],
                        "items": _NUMBER,
                        "minItems": 2,
                        "maxItems": 2,
                    },
                }
            },
            "required": ["points"],
            "additionalProperties": False,
        },
        {
            "type": "object",
            "properties": {
                "initial": _NUMBER,
                "changes": {
                    "type": "array",
                    "items": {
                        "type": "object",
                        "properties": {
                            "at": {"type": "number", "minimum": 0},
                            "to": _NUMBER,
                            "over": {"type": "number", "minimum": 0},
                        },
                        "required": ["at", "to"],
                        "additionalProperties": False,
                    },
                },
            },
            "required": ["initial"],
            "additionalProperties": False,
        },
    ],
}


@dataclass(frozen=True)
class Profile:
    """A piecewise-linear function of time, ``points = ((t0, v0), (t1, v1), ...)``.

    Constant before the first point and after the last one.

    Parameters
    ----------
    points : tuple of (float, float)
        Breakpoints ``(time in s, value)``, times ascending; the value is in the unit of the
        quantity the profile drives (SI inside: rad/s, N m, or a dimensionless scale).
    """

    points: tuple[tuple[float, float], ...]

    @staticmethod
    def constant(value: float) -> Profile:
        """A profile that is ``value`` at all times.

        Parameters
        ----------
        value : float
            The value, in the unit of the quantity the profile drives.

        Returns
        -------
        Profile
            One breakpoint at t = 0 s.

        Raises
        ------
        ConfigError
            ``value`` is not a finite number (a NaN profile would drive a NaN run).
        """
        return Profile(((0.0, check_number(value, "value")),))

    def scaled(self, k: float) -> Profile:
        """The same profile with every value multiplied by ``k`` (unit conversion).

        Parameters
        ----------
        k : float
            Factor, in (new unit)/(old unit), e.g. pi/30 for rpm -> rad/s (finite).

        Returns
        -------
        Profile
            The scaled profile, same times.
        """
        k = check_number(k, "k")
        return Profile(tuple((t, v * k) for t, v in self.points))

    def __call__(self, t):
        """Evaluate at time(s) ``t`` (Python side, for plots and tests)."""
        tt, vv = self.arrays()
        t = np.asarray(t, dtype=float)
        out = np.empty(t.shape)
        flat = out.reshape(-1)
        for k, tk in enumerate(t.reshape(-1)):
            flat[k] = _pwl_value(tt, vv, float(tk))
        return out if out.ndim else float(out)

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The breakpoints as two arrays.

        Returns
        -------
        t : ndarray
            Breakpoint times, s.
        v : ndarray
            Values at those times, in the unit of the quantity the profile drives.
        """
        t = np.array([p[0] for p in self.points], dtype=float)
        v = np.array([p[1] for p in self.points], dtype=float)
        return t, v

    def to_toml_value(self):
        """The profile as a scenario file writes it.

        Returns
        -------
        float or dict
            A number for a constant profile, else ``{"points": [[t, v], ...]}``.
        """
        if len(self.points) == 1:
            return self.points[0][1]
        return {"points": [list(p) for p in self.points]}

    @property
    def final(self) -> float:
        """The value after the last breakpoint, in the profile's unit."""
        return self.points[-1][1]

    @property
    def peak(self) -> float:
        """The largest magnitude the profile reaches (piecewise linear between breakpoints:
        at a breakpoint), in the profile's unit."""
        return float(max(abs(p[1]) for p in self.points))

    # as a pydantic field type: validated by parse_profile, written back in file form
    @classmethod
    def __get_pydantic_core_schema__(cls, source, handler):
        return core_schema.no_info_plain_validator_function(
            _validate,
            ref="Profile",
            serialization=core_schema.plain_serializer_function_ser_schema(Profile.to_toml_value),
        )

    @classmethod
    def __get_pydantic_json_schema__(cls, schema, handler):
        return dict(PROFILE_JSON_SCHEMA)


def _validate(value) -> Profile:
    # the field is named by the location pydantic reports (see imdrive.config.validation)
    return parse_profile("", value)


def _number(field: str, value) -> float:
    from imdrive.config.validation import _well_scaled_float

    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(field, f"must be a number, got {type(value).__name__}")
    try:
        value = float(value)
    except OverflowError:  # an int beyond a float
        raise ConfigError(field, "must be finite") from None
    if not math.isfinite(value):
        raise ConfigError(field, "must be finite")
    try:
        return _well_scaled_float(value)
    except ConfigError as exc:
        raise ConfigError(field, exc.rule) from None


def _checked_points(field: str, pts) -> Profile:
    """The breakpoints as a :class:`Profile`: each a ``[t, value]`` pair of numbers, times
    >= 0 (a profile starts with the run, as a change's ``at`` does) and non-decreasing."""
    if not isinstance(pts, list | tuple) or not pts:
        raise ConfigError(f"{field}.points", "must be a non-empty list of [t, value] pairs")
    out = []
    for k, p in enumerate(pts):
        f = f"{field}.points[{k}]"
        if not isinstance(p, list | tuple) or len(p) != 2:
            raise ConfigError(f, "must be a [t, value] pair")
        t, v = _number(f, p[0]), _number(f, p[1])
        if t < 0:
            raise ConfigError(f, f"times must be >= 0 (got {t:g} s)")
        if out and t < out[-1][0]:
            raise ConfigError(f, "times must be non-decreasing")
        out.append((t, v))
    return Profile(tuple(out))


def parse_profile(field: str, value) -> Profile:
    """Build a :class:`Profile` from its scenario-file form (see module docstring).

    Raises
    ------
    ConfigError
        Naming ``field`` and the broken rule.
    """
    if isinstance(value, Profile):  # built in Python: held to the file's rules
        return _checked_points(field, value.points)
    if not isinstance(value, dict):
        return Profile.constant(_number(field, value))
    keys = set(value)
    if "points" in keys:
        if keys - {"points"}:
            raise ConfigError(f"{field}.{sorted(keys - {'points'})[0]}", "unknown key")
        if not isinstance(value["points"], list):
            raise ConfigError(f"{field}.points", "must be a non-empty list of [t, value] pairs")
        return _checked_points(field, value["points"])
    unknown = keys - {"initial", "changes"}
    if unknown:
        raise ConfigError(f"{field}.{sorted(unknown)[0]}", "unknown key")
    if "initial" not in keys:
        raise ConfigError(f"{field}.initial", "is required with 'changes'")
    v = _number(f"{field}.initial", value["initial"])
    pts = [(0.0, v)]
    changes = value.get("changes", [])
    if not isinstance(changes, list):
        raise ConfigError(f"{field}.changes", "must be a list of {at, to[, over]} tables")
    t_last = 0.0
    for k, ch in enumerate(changes):
        f = f"{field}.changes[{k}]"
        if not isinstance(ch, dict):
            raise ConfigError(f, "must be a table {at, to[, over]}")
        bad = set(ch) - {"at", "to", "over"}
        if bad:
            raise ConfigError(f"{f}.{sorted(bad)[0]}", "unknown key")
        if "at" not in ch or "to" not in ch:
            raise ConfigError(f, "needs 'at' and 'to'")
        at = _number(f"{f}.at", ch["at"])
        to = _number(f"{f}.to", ch["to"])
        over = _number(f"{f}.over", ch.get("over", 0.0))
        if at < 0:
            raise ConfigError(f"{f}.at", "must be >= 0")
        if over < 0:
            raise ConfigError(f"{f}.over", "must be >= 0")
        if at < t_last:
            raise ConfigError(f"{f}.at", "changes must be in time order and must not overlap")
        pts.append((at, v))
        pts.append((at + over, to))
        v = to
        t_last = at + over
    return Profile(tuple(pts))


def _pwl_value(t_pts, v_pts, t: float) -> float:
    """Value at ``t`` of a piecewise-linear profile: the same arithmetic as the kernels'
    :func:`imdrive.kernels.profiles.pwl_eval` (right-continuous at steps, constant outside)."""
    n = len(t_pts)
    if t < t_pts[0]:
        return float(v_pts[0])
    i = 0
    while i + 1 < n and t_pts[i + 1] <= t:
        i += 1
    if i + 1 >= n:
        return float(v_pts[n - 1])
    dt = t_pts[i + 1] - t_pts[i]
    return float(v_pts[i] + (v_pts[i + 1] - v_pts[i]) * (t - t_pts[i]) / dt)
