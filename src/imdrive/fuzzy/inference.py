"""Fuzzy inference (eqs. 11, 12): quantisation, one cell, whole lookup tables.

The paper's compensator (Fig. 3) quantises the d-axis flux error ``E = e_d0`` and its change
``DE`` into 13 levels −6 … 6 (Tables I and II), infers the change of the resistance estimate
``CR`` from 49 rules ``if E is A and DE is B then CR is C`` with min-inference (eq. 11) and
centre-of-gravity defuzzification (eq. 12), and stores the result as a 13 × 13 lookup table
(Table III). This module computes those tables, in two variants (see :func:`infer`):
``"rules"`` — eq. (12) read literally, the default — and ``"universe"`` — the textbook Mamdani
max-aggregation over the 13-level universe. The loops run in the compiled
:mod:`imdrive.kernels.fuzzy`; this module validates arguments and converts results.

:func:`fuzzy_table` picks the table a drive uses (the printed Table III or a compiled one).
"""

from __future__ import annotations

import numpy as np

from imdrive.errors import ConfigError
from imdrive.fuzzy.tables import (
    FITTED_RULES,
    MEMBERSHIP,
    PAPER_TABLE_III,
    SET_PEAKS,
    THRESHOLDS,
    _check_membership,
    _check_rules,
)
from imdrive.kernels.fuzzy import _cell, _compile

__all__ = [
    "METHODS",
    "quantize_array",
    "infer",
    "compile_table_float",
    "round_level",
    "compile_table",
    "default_rules",
    "fuzzy_table",
]


#: Inference variants accepted by :func:`infer`, :func:`compile_table` and
#: :func:`~imdrive.fuzzy.fit.fit_rules_to_table`.
METHODS = ("rules", "universe")

# the jitted kernels take the method as an int
_METHOD_CODE = {"rules": 0, "universe": 1}


# --------------------------------------------------------------------------------------------
# Quantisation (Tables I/II)


def quantize_array(x) -> np.ndarray:
    """Vectorised :func:`~imdrive.kernels.fuzzy.quantize` (same intervals, NaN → 0) for arrays.

    Parameters
    ----------
    x : array_like of float
        Scaled inputs.

    Returns
    -------
    numpy.ndarray of int64
        Levels, same shape as ``x``.
    """
    x = np.asarray(x, dtype=np.float64)
    # searchsorted 'left' counts t < v, 'right' counts t <= v: the two interval closures
    pos = np.searchsorted(THRESHOLDS, x, side="left")
    neg = -np.searchsorted(THRESHOLDS, -x, side="right")
    out = np.where(x > 0.0, pos, neg)
    return np.where(np.isnan(x), 0, out).astype(np.int64)


# --------------------------------------------------------------------------------------------
# Inference (eqs. 11, 12)


def _method_code(method: str) -> int:
    if method not in _METHOD_CODE:
        raise ConfigError("fuzzy.method", f"must be one of {METHODS}, got {method!r}")
    return _METHOD_CODE[method]


def infer(
    e_level: int,
    de_level: int,
    rules,
    membership=MEMBERSHIP,
    method: str = "rules",
) -> float:
    """Crisp output CR for one pair of quantised inputs (eqs. 11 and 12).

    A rule ``(A, B) -> C`` fires with grade ``u = min(u_A(E), u_B(DE))`` (eq. 11).

    ``method="rules"`` (default) is eq. (12) as printed: ``CR = Σ u_n w_n / Σ u_n`` over the
    fired rules n, ``w_n`` the representative value (:data:`SET_PEAKS`) of rule n's output set.
    Several rules with the same output set are *summed*, each with its own grade — a weighted
    average of singletons (what is now called a zero-order Sugeno / "weighted average"
    defuzzifier).

    ``method="universe"`` is the common Mamdani reading: each fired rule clips its output set at
    ``u``, the clipped sets are combined by max over U, and CR is the centre of gravity
    ``Σ y μ(y) / Σ μ(y)`` over the 13 levels y. Rules sharing an output set then count once (the
    larger grade wins), and the output sets' shoulders move the result.

    The paper's text ("Σ over the N fired rules", "w_n the representative value of that rule's
    output set") describes the first; it is also the variant whose best rule base reproduces
    Table III far more closely (see :data:`FITTED_RULES`), so it is the default.

    Parameters
    ----------
    e_level, de_level : int
        Quantised E and DE, −6 … 6.
    rules : array_like of int, shape (7, 7)
        ``rules[e_set, de_set]`` = output set index, sets in :data:`SET_NAMES` order.
    membership : array_like, shape (13, 7)
        Membership grades (rows level −6 … 6); also used for the output sets.
    method : {"rules", "universe"}
        Defuzzification variant, see above.

    Returns
    -------
    float
        CR in levels (−6 … 6); 0.0 if no rule fires.
    """
    if not (-6 <= e_level <= 6 and -6 <= de_level <= 6):
        raise ConfigError("fuzzy.level", "levels must lie in -6..6")
    v = _cell(
        int(e_level) + 6,
        int(de_level) + 6,
        _check_rules(rules),
        _check_membership(membership),
        SET_PEAKS,
        _method_code(method),
    )
    return 0.0 if np.isnan(v) else float(v)


def compile_table_float(rules, method: str = "rules", membership=MEMBERSHIP) -> np.ndarray:
    """Unrounded lookup table: :func:`infer` at every (E, DE) level pair.

    Parameters
    ----------
    rules : array_like of int, shape (7, 7)
        Rule base, see :func:`infer`.
    method : {"rules", "universe"}
        Defuzzification variant.
    membership : array_like, shape (13, 7)
        Membership grades.

    Returns
    -------
    numpy.ndarray, shape (13, 13), float64
        Rows E = −6 … 6, columns DE = −6 … 6; cells where nothing fires are 0.
    """
    t = _compile(
        _check_rules(rules), _check_membership(membership), SET_PEAKS, _method_code(method)
    )
    return np.where(np.isnan(t), 0.0, t)


def round_level(x) -> np.ndarray:
    """Round CR values to the nearest integer level, halves away from zero.

    Values are first rounded to 9 decimals so that a COG that is a half-integer in exact
    arithmetic (e.g. 2.5 computed as 2.4999999999999996) rounds the same way on every platform.
    Half away from zero keeps a table compiled from antisymmetric rules antisymmetric, which
    round-half-to-even would not guarantee, and it is what Table III shows: with
    :data:`FITTED_RULES_MONOTONE` 30 cells have an exact .5 COG (row E = −5: −5.5, −4.5, …,
    −0.5), and 29 of them are printed rounded away from zero (9 would match half-to-even).

    Parameters
    ----------
    x : array_like of float

    Returns
    -------
    numpy.ndarray of int64
    """
    x = np.round(np.asarray(x, dtype=np.float64), 9)
    return (np.sign(x) * np.floor(np.abs(x) + 0.5)).astype(np.int64)


def compile_table(rules, method: str = "rules", membership=MEMBERSHIP) -> np.ndarray:
    """Lookup table of output levels, like Table III: :func:`compile_table_float` rounded.

    Parameters
    ----------
    rules : array_like of int, shape (7, 7)
        Rule base, see :func:`infer`.
    method : {"rules", "universe"}
        Defuzzification variant.
    membership : array_like, shape (13, 7)
        Membership grades.

    Returns
    -------
    numpy.ndarray, shape (13, 13), int64
        Rows E = −6 … 6, columns DE = −6 … 6, rounded by :func:`round_level`.
    """
    return round_level(compile_table_float(rules, method, membership))


def default_rules() -> np.ndarray:
    """Classic diagonal rule base ``CR = clip(E + DE)`` in set-index terms.

    With sets numbered −3 … 3 (NB … PB) the output set is ``clip(e + de, −3, 3)``; it contains
    the paper's rules (1) NB, NB → NB and (2) PB, PB → PB, and is antisymmetric:
    ``rules[6-a, 6-b] = 6 - rules[a, b]``.

    Returns
    -------
    numpy.ndarray, shape (7, 7), int64
        ``rules[e_set, de_set]`` = output set index 0 … 6.
    """
    a = np.arange(7)
    return np.clip(a[:, None] + a[None, :] - 3, 0, 6).astype(np.int64)


# --------------------------------------------------------------------------------------------
# The table a drive uses


def fuzzy_table(source: str = "paper", rules=None, method: str = "rules") -> np.ndarray:
    """The lookup table a drive should use.

    Parameters
    ----------
    source : {"paper", "rules"}
        ``"paper"``: Table III as printed (row −6 repaired); ``"rules"``: compiled from
        ``rules`` with ``method``.
    rules : array_like of int, shape (7, 7), optional
        Rule base for ``source="rules"``; defaults to :data:`FITTED_RULES`.
    method : {"rules", "universe"}
        Defuzzification variant for ``source="rules"``.

    Returns
    -------
    numpy.ndarray, shape (13, 13), int64
        A fresh, writable array.
    """
    if source == "paper":
        if rules is not None:
            raise ConfigError("fuzzy.rules", "only used with source='rules'")
        return PAPER_TABLE_III.copy()
    if source == "rules":
        return compile_table(FITTED_RULES if rules is None else rules, method)
    raise ConfigError("fuzzy.source", f"must be 'paper' or 'rules', got {source!r}")
