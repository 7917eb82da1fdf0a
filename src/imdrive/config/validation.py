"""The validation layer under every settings class: pydantic v2, reported as :class:`ConfigError`.

Settings classes are ``pydantic.dataclasses.dataclass`` es (frozen, unknown keys forbidden), so
they stay stdlib dataclasses: ``dataclasses.replace``, ``fields`` and ``is_dataclass`` work and
``replace`` validates again. :func:`settings` makes one; its constructor raises
:class:`~imdrive.errors.ConfigError` (one line, ``field.path: rule``) instead of pydantic's
``ValidationError``, with the path prefixed by the class's place in a scenario
(``machine.R1_ohm``, ``plant.thermal.tau1_s``).

Scalar types are strict (a boolean is not a number, a string is not an integer, ``nan`` and
``inf`` are refused); an integer-valued float is accepted as an integer and numpy scalars as
the Python number they hold.

A :class:`ConfigError` raised inside a validator names its field *relative to where pydantic
reports it*: ``""`` for the value itself, ``".points[1]"`` or ``"[2]"`` below it, ``"Ts_s"``
for a field of the class a model validator checks. :func:`config_error` prefixes it with that
location.
"""

from __future__ import annotations

import functools
import re
from typing import Annotated, Any

import numpy as np
from pydantic import AfterValidator, BeforeValidator, ConfigDict, Field, Strict, ValidationError
from pydantic.dataclasses import dataclass as _pydantic_dataclass
from pydantic_core import core_schema

from imdrive.errors import ConfigError

CONFIG = ConfigDict(
    extra="forbid",  # unknown keys are errors
    allow_inf_nan=False,  # every float is finite
    revalidate_instances="never",  # a section object passed in is already valid
)


# ------------------------------------------------------------------------------------------
# scalar types


def _scalar(value):
    """A numpy scalar as the Python number it holds; anything else unchanged."""
    return value.item() if isinstance(value, np.generic) else value


def _integral(value):
    """An integer-valued float (``2.0``) or a numpy integer as an int; anything else unchanged."""
    if isinstance(value, float) and value.is_integer():
        return int(value)
    return _scalar(value)


#: Magnitudes a float setting may have (besides 0): every setting is a physical quantity in SI
#: units, far inside this range, and a product or quotient of two such values stays a normal
#: finite float (a subnormal 5e-324 times a period of 1e-4 s is 0, a divisor). Longer products
#: (a gain from several settings) are checked where they are derived.
FLOAT_MIN_MAGNITUDE = 1e-150
FLOAT_MAX_MAGNITUDE = 1e150
#: Largest magnitude of an integer setting: exact as a float, far inside a 64-bit record field.
INT_MAX_MAGNITUDE = 2**53


def _well_scaled_float(value: float) -> float:
    """Refuse a nonzero float outside :data:`FLOAT_MIN_MAGNITUDE` .. :data:`FLOAT_MAX_MAGNITUDE`
    in magnitude: derived quantities computed from it would overflow or vanish."""
    if value != 0.0 and not FLOAT_MIN_MAGNITUDE <= abs(value) <= FLOAT_MAX_MAGNITUDE:
        raise ConfigError(
            "",
            f"must be 0 or between {FLOAT_MIN_MAGNITUDE:g} and {FLOAT_MAX_MAGNITUDE:g} in "
            f"magnitude (got {value!r}): derived quantities would overflow or vanish",
        )
    return value


def _well_scaled_int(value: int) -> int:
    """Refuse an integer beyond :data:`INT_MAX_MAGNITUDE` in magnitude (a 64-bit record field
    and a float must hold it exactly)."""
    if abs(value) > INT_MAX_MAGNITUDE:
        raise ConfigError("", f"must be at most 2^53 in magnitude (got {value})")
    return value


Float = Annotated[float, Strict(), BeforeValidator(_scalar), AfterValidator(_well_scaled_float)]
"""A finite number, 0 or of magnitude 1e-150 .. 1e150 (an int is accepted and stored as a
float; a bool or a string is not)."""
Int = Annotated[int, Strict(), BeforeValidator(_integral), AfterValidator(_well_scaled_int)]
"""An integer of magnitude <= 2^53 (``2.0`` is accepted as 2; ``1.5``, ``"2"`` and ``true``
are not)."""
Bool = Annotated[bool, Strict(), BeforeValidator(_scalar)]
"""``true`` or ``false`` (not 0/1)."""
Str = Annotated[str, Strict()]

NAME_MAX = 100
_NAME_RE = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]*")
NAME_RULE = (
    f"must be 1 to {NAME_MAX} characters from A-Z a-z 0-9 . _ + -, starting with a letter or "
    "digit (it names the output folder)"
)


def check_name(value: str) -> str:
    """A run's or sweep's name, which becomes a folder name: a safe character set and length.

    Refuses ``..``, ``/``, an absolute path, an empty name and one over :data:`NAME_MAX`
    characters with :class:`ConfigError` (field ``""``: the caller's field).
    """
    if not (isinstance(value, str) and len(value) <= NAME_MAX and _NAME_RE.fullmatch(value)):
        raise ConfigError("", f"{NAME_RULE}, got {_show(value)}")
    return value


def slug(text: str, default: str = "sweep") -> str:
    """``text`` made a valid name (:func:`check_name`): other characters become ``-``."""
    out = re.sub(r"[^A-Za-z0-9._+-]", "-", text).lstrip("._+-")[:NAME_MAX]
    return out or default


Name = Annotated[str, Strict(), AfterValidator(check_name)]
"""A name that becomes a folder name (:func:`check_name`)."""


def setting(
    description: str,
    unit: str | None = None,
    *,
    default_doc: str | None = None,
    derived: bool = False,
    **constraints,
):
    """Field metadata of a setting: what it means, its unit, its constraints (``gt=0``, ...).

    ``default_doc`` says what a ``None`` default means (``"the plant's"``); the docs print it
    in place of the default. ``derived=True``: the unset value depends on the scenario and is
    resolved by :mod:`imdrive.config.defaults`, whose entry for the key holds the rule the docs
    print (written there once). Use inside ``Annotated[...]``; the default is the plain value
    after ``=`` so that ``dataclasses.fields`` shows it.
    """
    extra: dict[str, Any] = {}
    if unit:
        extra["unit"] = unit
    if default_doc:
        extra["default_doc"] = default_doc
    if derived:
        extra["derived"] = True
    return Field(description=description, json_schema_extra=extra or None, **constraints)


class ProfileValues:
    """Constraint on every breakpoint value of a :class:`~imdrive.config.profiles.Profile`.

    ``Annotated[Profile, ProfileValues(gt=0)]``; the error says ``must be > 0`` on the field.
    """

    def __init__(self, *, gt: float | None = None, ge: float | None = None):
        self.gt = gt
        self.ge = ge

    @property
    def rule(self) -> str:
        return f"> {self.gt:g}" if self.gt is not None else f">= {self.ge:g}"

    def _check(self, profile):
        if profile is None:
            return profile
        for _, v in profile.points:
            if (self.gt is not None and not v > self.gt) or (
                self.ge is not None and not v >= self.ge
            ):
                raise ConfigError("", f"must be {self.rule}")
        return profile

    def __get_pydantic_core_schema__(self, source, handler):
        return core_schema.no_info_after_validator_function(self._check, handler(source))

    def __repr__(self) -> str:
        return f"ProfileValues({self.rule})"


# ------------------------------------------------------------------------------------------
# settings classes


def settings(path: str):
    """Class decorator: a frozen pydantic dataclass validated as the scenario table ``path``.

    ``path`` (``"machine"``, ``"plant.thermal"``; ``""`` for the scenario itself) prefixes the
    field named by a :class:`ConfigError` when the class is built directly (``MachineParams(...)``,
    ``dataclasses.replace``).
    """

    def wrap(cls):
        cls = _pydantic_dataclass(frozen=True, config=CONFIG)(cls)
        pydantic_init = cls.__init__

        @functools.wraps(pydantic_init)
        def __init__(self, *args, **kwargs):
            try:
                pydantic_init(self, *args, **kwargs)
            except ValidationError as exc:
                raise config_error(exc, path) from None

        cls.__init__ = __init__
        cls.table_path = path
        return cls

    return wrap


def validate(cls, data, path: str = ""):
    """``cls`` built from its TOML-shaped dictionary ``data``; errors as :class:`ConfigError`."""
    try:
        return cls.__pydantic_validator__.validate_python(data)
    except ValidationError as exc:
        raise config_error(exc, path) from None


# ------------------------------------------------------------------------------------------
# ValidationError -> ConfigError


def join_path(head: str, tail: str) -> str:
    """``head`` and a relative field path: ``a`` + ``b`` -> ``a.b``, ``a`` + ``[1]`` -> ``a[1]``."""
    if not head:
        return tail.lstrip(".")
    if not tail:
        return head
    if tail[0] in ".[":
        return head + tail
    return f"{head}.{tail}"


def _loc_path(prefix: str, loc) -> str:
    path = prefix
    for part in loc:
        path = join_path(path, f"[{part}]" if isinstance(part, int) else str(part))
    return path


def _show(value) -> str:
    try:
        text = repr(value)
    except RecursionError:  # a value nested thousands deep: reprlib stops at 6 levels
        import reprlib

        text = reprlib.repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _bound(value) -> str:
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)


_COMPARISONS = {
    "greater_than": ("gt", ">"),
    "greater_than_equal": ("ge", ">="),
    "less_than": ("lt", "<"),
    "less_than_equal": ("le", "<="),
}
_TYPE_RULES = {
    "bool_type": "must be true or false",
    "bool_parsing": "must be true or false",
    "int_type": "must be an integer",
    "int_parsing": "must be an integer",
    "int_from_float": "must be an integer",
    "float_type": "must be a number",
    "float_parsing": "must be a number",
    "string_type": "must be a string",
}
_TABLE_TYPES = {"dataclass_type", "dataclass_exact_type", "dict_type", "model_type"}
_UNKNOWN_KEY = {"extra_forbidden", "unexpected_keyword_argument"}


def _rule(err: dict) -> tuple[str, str]:
    """``(relative field, rule)`` of one pydantic error (see :func:`config_error`)."""
    kind = err["type"]
    ctx = err.get("ctx") or {}
    value = err.get("input")
    if kind == "value_error" and isinstance(ctx.get("error"), ConfigError):
        inner = ctx["error"]
        return inner.field, inner.rule
    if kind in _COMPARISONS:
        key, op = _COMPARISONS[kind]
        bound = ctx.get(key)
        if isinstance(bound, float) and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)  # the field is a float: show the value as one
        return "", f"must be {op} {_bound(bound)} (got {value})"
    if kind == "finite_number":
        return "", "must be finite"
    if kind in _TYPE_RULES:
        return "", f"{_TYPE_RULES[kind]}, got {_show(value)}"
    if kind == "literal_error":
        choices = re.findall(r"'([^']*)'", ctx.get("expected", ""))
        return "", "must be one of " + ", ".join(repr(c) for c in choices)
    if kind in _UNKNOWN_KEY:
        return "", "unknown key"
    if kind in ("missing", "missing_argument"):
        return "", "is required"
    if kind in _TABLE_TYPES:
        return "", "must be a table"
    if kind == "unexpected_positional_argument":
        return "", "too many positional arguments"
    if kind == "multiple_argument_values":
        return "", "given twice"
    if kind == "value_error" and "error" in ctx:
        return "", str(ctx["error"])
    return "", err["msg"][:1].lower() + err["msg"][1:]


def config_error(exc: ValidationError, prefix: str = "") -> ConfigError:
    """The first error of ``exc`` as a one-line :class:`ConfigError` ``field.path: rule``.

    ``prefix`` is the table the validated object sits at (``"machine"``); the location pydantic
    reports is appended, then the field a :class:`ConfigError` raised inside a validator names.
    """
    err = exc.errors(include_url=False)[0]
    field, rule = _rule(err)
    path = join_path(_loc_path(prefix, err["loc"]), field)
    return ConfigError(path or "scenario", rule)
