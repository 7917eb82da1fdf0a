"""Fuzzy-logic rotor-resistance compensator: quantisation, inference and the lookup table (§4).

The paper's compensator (Fig. 3) quantises the d-axis flux error ``E = e_d0`` and its change
``DE`` into 13 levels −6 … 6 (Tables I and II), infers the change of the resistance estimate
``CR`` from 49 rules ``if E is A and DE is B then CR is C`` with min-inference (eq. 11) and
centre-of-gravity defuzzification (eq. 12), and stores the result as a 13 × 13 lookup table
(Table III). The drive kernel only ever sees that table, through :func:`lookup`.

This module holds

* the paper's data: :data:`THRESHOLDS`, :data:`MEMBERSHIP`, :data:`PAPER_TABLE_III`;
* the inference (:func:`infer`) and table compilation (:func:`compile_table`), in two variants
  (see :func:`infer` for the difference): ``"rules"`` — eq. (12) read literally, the default —
  and ``"universe"`` — the textbook Mamdani max-aggregation over the 13-level universe;
* a search for the unprinted rule base that best reproduces Table III
  (:func:`fit_rules_to_table`, results cached as :data:`FITTED_RULES` and
  :data:`FITTED_RULES_MONOTONE`);
* helpers to compare and print tables, and the numba-compiled :func:`quantize` / :func:`lookup`.

Levels are integers −6 … 6 and are stored at array index ``level + 6``; fuzzy sets are indexed
0 … 6 in the order of :data:`SET_NAMES`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from imdrive.errors import ConfigError
from imdrive.kernels.fuzzy import (
    THRESHOLDS,
    _cell,
    _compile,
    _descend,
    _violations,
    lookup,
    quantize,
)

__all__ = [
    "THRESHOLDS",
    "LEVELS",
    "SET_NAMES",
    "SET_PEAKS",
    "MEMBERSHIP",
    "PAPER_TABLE_III",
    "METHODS",
    "DEFAULT_FIT_STARTS",
    "FITTED_RULES",
    "FITTED_RULES_MONOTONE",
    "FitResult",
    "quantize",
    "quantize_array",
    "infer",
    "compile_table_float",
    "round_level",
    "compile_table",
    "default_rules",
    "table_score",
    "fit_rules_to_table",
    "table_diff",
    "format_table",
    "format_rules",
    "lookup",
    "fuzzy_table",
]

# --------------------------------------------------------------------------------------------
# Paper data (Tables I-III)

#: Quantisation thresholds of Tables I/II, dimensionless. The paper's values are in units of
#: 1e-6 (of an unstated flux unit); the caller multiplies e_d0 by an input scaling gain (e.g.
#: 1e6 per Wb) before quantising, so the gain is a tuning parameter, not part of this table.
# THRESHOLDS is defined with the compiled quantiser (imdrive.kernels.fuzzy) and imported above

#: The 13 quantisation levels, in array-index order.
LEVELS = np.arange(-6, 7, dtype=np.int64)

#: The seven primary fuzzy sets on the universe U = {−6, …, 6}, in set-index order.
SET_NAMES = ("NB", "NM", "NS", "ZE", "PS", "PM", "PB")

#: Representative value w_n of each output set in eq. (12). The paper does not state it; we take
#: the level at which the set's grade is 1.0 (its peak, Table I), which for these symmetric,
#: evenly spaced sets is also the set's own centre of gravity over U.
SET_PEAKS = np.array([-6.0, -4.0, -2.0, 0.0, 2.0, 4.0, 6.0])

#: Membership grades u(level) of the seven sets, Table I as repaired in PAPER.md (the OCR repeats
#: the rows of levels 0 and 1 at levels 2 and 3). Rows: level −6 … 6; columns: NB … PB.
MEMBERSHIP = np.array(
    [
        [1.0, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0],  # -6
        [0.7, 0.7, 0.0, 0.0, 0.0, 0.0, 0.0],  # -5
        [0.3, 1.0, 0.3, 0.0, 0.0, 0.0, 0.0],  # -4
        [0.0, 0.7, 0.7, 0.0, 0.0, 0.0, 0.0],  # -3
        [0.0, 0.3, 1.0, 0.3, 0.0, 0.0, 0.0],  # -2
        [0.0, 0.0, 0.7, 0.7, 0.0, 0.0, 0.0],  # -1
        [0.0, 0.0, 0.3, 1.0, 0.3, 0.0, 0.0],  # 0
        [0.0, 0.0, 0.0, 0.7, 0.7, 0.0, 0.0],  # 1
        [0.0, 0.0, 0.0, 0.3, 1.0, 0.3, 0.0],  # 2
        [0.0, 0.0, 0.0, 0.0, 0.7, 0.7, 0.0],  # 3
        [0.0, 0.0, 0.0, 0.0, 0.3, 1.0, 0.3],  # 4
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.7, 0.7],  # 5
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.3, 1.0],  # 6
    ]
)

#: Table III as printed: output level of CR, rows E = −6 … 6, columns DE = −6 … 6.
#: Repair: the OCR lost the first entry of row E = −6 (12 values survive); that row is taken equal
#: to row −5, whose entries it matches position by position. Row −4 (non-monotone) and the
#: departures from antisymmetry are kept as printed.
PAPER_TABLE_III = np.array(
    [
        [-6, -6, -5, -5, -4, -4, -3, -3, -2, -2, -1, -1, 0],  # -6 (repaired: = row -5)
        [-6, -6, -5, -5, -4, -4, -3, -3, -2, -2, -1, -1, 0],  # -5
        [-4, -4, -4, -4, -3, -2, -2, -2, -1, -1, 0, 0, 0],  # -4
        [-5, -5, -4, -4, -3, -3, -2, -2, -1, -1, 0, 0, 0],  # -3
        [-4, -4, -3, -3, -2, -2, -1, -1, 0, 0, 0, 1, 1],  # -2
        [-4, -4, -2, -2, -1, -1, -1, 0, 1, 1, 1, 2, 2],  # -1
        [-3, -3, -2, -1, -1, 0, 0, 0, 1, 1, 2, 3, 3],  # 0
        [-2, -2, -1, -1, 0, 1, 1, 1, 2, 3, 4, 4, 4],  # 1
        [-1, -1, 0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4],  # 2
        [0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5],  # 3
        [0, 0, 1, 1, 2, 2, 2, 3, 4, 4, 4, 5, 5],  # 4
        [0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6],  # 5
        [0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6],  # 6
    ],
    dtype=np.int64,
)

#: Inference variants accepted by :func:`infer`, :func:`compile_table`, :func:`fit_rules_to_table`.
METHODS = ("rules", "universe")

# the jitted kernels take the method as an int
_METHOD_CODE = {"rules": 0, "universe": 1}

for _a in (THRESHOLDS, LEVELS, SET_PEAKS, MEMBERSHIP, PAPER_TABLE_III):
    _a.flags.writeable = False  # shared module constants: a stray in-place edit must fail loudly


# --------------------------------------------------------------------------------------------
# Quantisation (Tables I/II)


def quantize_array(x) -> np.ndarray:
    """Vectorised :func:`quantize` (same intervals, NaN → 0) for arrays in Python code.

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


def _check_rules(rules) -> np.ndarray:
    r = np.asarray(rules)
    if r.shape != (7, 7) or not np.issubdtype(r.dtype, np.integer):
        raise ConfigError("fuzzy.rules", "must be a 7x7 integer array of set indices")
    if r.min() < 0 or r.max() > 6:
        raise ConfigError("fuzzy.rules", "set indices must lie in 0..6")
    # always a fresh writable C array: numba compiles read-only arrays (our constants) as a
    # separate type, and one specialisation per kernel keeps the compile time down
    return np.array(r, dtype=np.int64, order="C")


def _check_membership(membership) -> np.ndarray:
    m = np.array(membership, dtype=np.float64, order="C")  # fresh and writable, as above
    if m.shape != (13, 7):
        raise ConfigError("fuzzy.membership", "must be a 13x7 array (levels x sets)")
    return m


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
# Fitting the unprinted rule base to Table III


def table_score(table, target=PAPER_TABLE_III) -> tuple[int, int]:
    """Distance of an integer table from a target: (differing cells, Σ |difference|).

    Parameters
    ----------
    table, target : array_like of int, shape (13, 13)

    Returns
    -------
    tuple of int
        Number of cells that differ, and the sum of absolute differences.
    """
    d = np.abs(np.asarray(table, dtype=np.int64) - np.asarray(target, dtype=np.int64))
    return int(np.count_nonzero(d)), int(d.sum())


def _move_list() -> np.ndarray:
    # rows (a, b, c, e): the 49 single-rule moves (c, e) = (a, b), then every pair of rules
    # whose sets are adjacent in E and in DE (they share cells, so a change that helps only when
    # both move together is invisible to single moves)
    singles = [(a, b, a, b) for a in range(7) for b in range(7)]
    pairs = [
        (a, b, c, e)
        for a in range(7)
        for b in range(7)
        for c in range(a, min(a + 2, 7))
        for e in range(max(b - 1, 0), min(b + 2, 7))
        if (c, e) > (a, b)
    ]
    return np.array(singles + pairs, dtype=np.int64)


_MOVES = _move_list()


def _half_rules() -> np.ndarray:
    # CR set = (E set + DE set) / 2: Table III grows by about one level per two steps of E or DE
    a = np.arange(7)
    return round_level((a[:, None] + a[None, :]) / 2.0)


_REGULARITY = {"none": 0, "tiebreak": 1, "monotone": 2}

#: Number of seeded random restarts :func:`fit_rules_to_table` uses by default.
DEFAULT_FIT_STARTS = 4


@dataclass(frozen=True, eq=False)  # eq on array fields would be ambiguous
class FitResult:
    """Outcome of :func:`fit_rules_to_table`.

    Attributes
    ----------
    rules : numpy.ndarray, shape (7, 7), int64
        Best rule base found.
    table : numpy.ndarray, shape (13, 13), int64
        Its compiled, rounded table.
    n_diff : int
        Cells where ``table`` differs from the target.
    abs_diff : int
        Σ |table − target|.
    """

    rules: np.ndarray
    table: np.ndarray
    n_diff: int
    abs_diff: int


def fit_rules_to_table(
    target=PAPER_TABLE_III,
    method: str = "rules",
    membership=MEMBERSHIP,
    n_starts: int = DEFAULT_FIT_STARTS,
    n_kicks: int = 60,
    seed: int = 0,
    starts=None,
    regularity: str = "tiebreak",
) -> FitResult:
    """Search the 49-rule base whose compiled table comes closest to ``target`` (Table III).

    The paper prints Table III but not the 49 rules behind it. Each rule picks one of 7 output
    sets (7^49 bases), so we run an iterated local search:

    1. starts: the diagonal :func:`default_rules`, the "half" base ``(E + DE) / 2`` in set
       indices (Table III rises about one level per two steps), any ``starts`` given, and
       ``n_starts`` seeded random bases;
    2. from each start, descend with single-rule moves and then moves of two neighbouring rules
       (sets adjacent in E and DE) until neither improves; each move is scored only on the cells
       the changed rules fire in;
    3. then ``n_kicks`` times: randomly reassign 2-4 rules of the best base (seeded), descend,
       and keep the result if it is better.

    This runs twice: first restricted to monotone rule bases (output set non-decreasing in E
    and DE), where local search converges well, then — unless
    ``regularity="monotone"`` — from that optimum without the restriction.

    The objective is lexicographic: the number of differing cells, then Σ |difference|, then
    (``regularity="tiebreak"``) the monotonicity violation V of the rules, then the squared
    residual of the unrounded table. The result is fully determined by the arguments; with
    the defaults it takes about 2 s.

    Results for the printed Table III (method "rules"; the same for seeds 0-9):

    * defaults: :data:`FITTED_RULES`, 11 differing cells, Σ |difference| = 11, V = 8;
    * ``regularity="monotone"``: :data:`FITTED_RULES_MONOTONE`, 12 cells, Σ = 12, V = 0. This
      base is also antisymmetric and its table exactly antisymmetric; 6 of its 12 misses are
      in the printed row E = −4, which PAPER.md already flags as breaking the pattern. It is the
      more plausible reconstruction of the authors' rules: the unconstrained optimum buys one
      cell with eight non-monotone rules.
    * ``method="universe"``: 37 cells, Σ = 39 with the defaults (36 / 38 in a long search;
      44 / 44 if monotone). The Mamdani reading cannot reproduce Table III — it cannot even
      reach ±6, the COG of NB over U being −5.35 — evidence that the paper used the literal
      eq. (12).

    Parameters
    ----------
    target : array_like of int, shape (13, 13)
        Table to reproduce.
    method : {"rules", "universe"}
        Defuzzification variant used to compile candidate tables.
    membership : array_like, shape (13, 7)
        Membership grades.
    n_starts : int
        Seeded random starting bases, in addition to the two structured ones.
    n_kicks : int
        Perturbation rounds after the restarts.
    seed : int
        Seed of :func:`numpy.random.default_rng` for the random starts and kicks.
    starts : iterable of array_like, optional
        Extra starting rule bases.
    regularity : {"none", "tiebreak", "monotone"}
        Use of the monotonicity violation V (total size of the steps where the output set
        decreases as E or DE grows): ``"none"`` ignores it; ``"tiebreak"`` ranks it after
        Σ |difference|; ``"monotone"`` ranks it first, i.e. searches monotone rule bases only.

    Returns
    -------
    FitResult
    """
    code = _method_code(method)
    if regularity not in _REGULARITY:
        raise ConfigError("fuzzy.regularity", f"must be one of {tuple(_REGULARITY)}")
    reg = _REGULARITY[regularity]
    m = _check_membership(membership)
    tgt = np.ascontiguousarray(target, dtype=np.float64)
    if tgt.shape != (13, 13):
        raise ConfigError("fuzzy.target", "must be a 13x13 table")
    rng = np.random.default_rng(seed)
    cands = [default_rules(), _half_rules()]
    cands += [_check_rules(s) for s in (starts or ())]
    cands += [rng.integers(0, 7, size=(7, 7)).astype(np.int64) for _ in range(n_starts)]

    def key(r, reg_):
        # the same cost vector _descend works with, as a comparable tuple
        v = _compile(r, m, SET_PEAKS, code)
        v = np.where(np.isnan(v), 0.0, v)
        nd, ad = table_score(round_level(v), tgt.astype(np.int64))
        viol = int(_violations(r))
        sse = round(float(((v - tgt) ** 2).sum()), 9)
        return (viol if reg_ == 2 else 0, nd, ad, viol if reg_ == 1 else 0, sse)

    def ils(starts_, reg_, kicks):
        # iterated local search: descend from every start, then kick the best and re-descend
        best, best_key = None, None
        for c in starts_:
            r = _descend(c.copy(), tgt, m, SET_PEAKS, code, reg_, _MOVES)
            k = key(r, reg_)
            if best_key is None or k < best_key:
                best, best_key = r, k
        for _ in range(kicks):
            r = best.copy()
            n = int(rng.integers(2, 5))
            idx = rng.choice(49, size=n, replace=False)
            r.flat[idx] = rng.integers(0, 7, size=n)
            r = _descend(r, tgt, m, SET_PEAKS, code, reg_, _MOVES)
            k = key(r, reg_)
            if k < best_key:
                best, best_key = r, k
        return best, best_key

    # stage 1: monotone bases only; local search converges well in that smoother landscape,
    # and its optimum is a good start for the unconstrained search of stage 2
    best, best_key = ils(cands, _REGULARITY["monotone"], n_kicks)
    if reg != _REGULARITY["monotone"]:
        best, best_key = ils([best], reg, n_kicks)
    table = compile_table(best, method, m)
    return FitResult(best, table, best_key[1], best_key[2])


#: Rule base fitted to Table III by ``fit_rules_to_table()`` (all defaults: method "rules",
#: regularity "tiebreak"), pasted here as data so importing the module costs nothing.
#: ``FITTED_RULES[e_set, de_set]`` is the output set index; rows E = NB … PB, columns
#: DE = NB … PB. Compiled with method "rules" it differs from the printed Table III in 11 cells,
#: each by one level: (E, DE) = (−6, 1), (−6, 4), (−4, −6), (−4, −5), (−4, −2), (−4, −1),
#: (−4, 2), (−1, −4), (1, 2), (1, 3), (1, 4).
FITTED_RULES = np.array(
    [
        [0, 0, 1, 1, 3, 1, 4],  # NB
        [0, 1, 1, 2, 1, 3, 3],  # NM
        [1, 1, 2, 2, 4, 3, 3],  # NS
        [1, 2, 3, 3, 3, 4, 5],  # ZE
        [3, 3, 3, 4, 4, 5, 5],  # PS
        [3, 3, 4, 4, 5, 5, 6],  # PM
        [3, 4, 4, 5, 5, 6, 6],  # PB
    ],
    dtype=np.int64,
)

#: Best monotone rule base, ``fit_rules_to_table(regularity="monotone")``: 12 differing cells,
#: each by one level; monotone, antisymmetric (``r[6-a, 6-b] = 6 - r[a, b]``), and its compiled
#: table is exactly antisymmetric. See :func:`fit_rules_to_table` for why it may be the better
#: reconstruction.
FITTED_RULES_MONOTONE = np.array(
    [
        [0, 0, 1, 1, 2, 2, 3],  # NB
        [0, 1, 1, 2, 2, 3, 3],  # NM
        [1, 1, 2, 2, 3, 3, 3],  # NS
        [1, 2, 3, 3, 3, 4, 5],  # ZE
        [3, 3, 3, 4, 4, 5, 5],  # PS
        [3, 3, 4, 4, 5, 5, 6],  # PM
        [3, 4, 4, 5, 5, 6, 6],  # PB
    ],
    dtype=np.int64,
)
FITTED_RULES_MONOTONE.flags.writeable = False
FITTED_RULES.flags.writeable = False


# --------------------------------------------------------------------------------------------
# Comparing, printing, using tables


def table_diff(a, b) -> list[tuple[int, int, int, int]]:
    """Cells where two 13 × 13 tables differ.

    Parameters
    ----------
    a, b : array_like, shape (13, 13)

    Returns
    -------
    list of tuple
        ``(e_level, de_level, a_value, b_value)`` in row-major order, levels −6 … 6.
    """
    a = np.asarray(a)
    b = np.asarray(b)
    if a.shape != (13, 13) or b.shape != (13, 13):
        raise ConfigError("fuzzy.table", "tables must be 13x13")
    return [
        (int(i) - 6, int(j) - 6, a[i, j].item(), b[i, j].item())
        for i, j in zip(*np.nonzero(a != b), strict=True)
    ]


def format_table(table, fmt: str = "text") -> str:
    r"""Render a 13 × 13 table with its E (rows) and DE (columns) levels.

    Parameters
    ----------
    table : array_like, shape (13, 13)
        Integer or float table.
    fmt : {"text", "csv"}
        ``"text"``: right-aligned grid with a ``E\DE`` header row and a rule under it;
        ``"csv"``: header row ``E\DE,-6,...,6`` then one line per E level.

    Returns
    -------
    str
        Lines joined by ``\n``, with a trailing newline.
    """
    t = np.asarray(table)
    if t.shape != (13, 13):
        raise ConfigError("fuzzy.table", "table must be 13x13")

    def cell(v):
        if np.issubdtype(t.dtype, np.integer):
            return str(int(v))
        return f"{float(v):.3f}"

    rows = [[cell(v) for v in row] for row in t]
    if fmt == "csv":
        lines = ["E\\DE," + ",".join(str(k) for k in LEVELS)]
        lines += [f"{k}," + ",".join(r) for k, r in zip(LEVELS, rows, strict=True)]
        return "\n".join(lines) + "\n"
    if fmt != "text":
        raise ConfigError("fuzzy.fmt", f"must be 'text' or 'csv', got {fmt!r}")
    w = max(3, max(len(s) for r in rows for s in r))
    head = "E\\DE |" + "".join(f" {k:>{w}d}" for k in LEVELS)
    lines = [head, "-" * len(head)]
    lines += [
        f"{k:>4d} |" + "".join(f" {s:>{w}}" for s in r) for k, r in zip(LEVELS, rows, strict=True)
    ]
    return "\n".join(lines) + "\n"


def format_rules(rules) -> str:
    """Render a 7 × 7 rule base as a grid of set names (rows E, columns DE).

    Parameters
    ----------
    rules : array_like of int, shape (7, 7)

    Returns
    -------
    str
    """
    r = _check_rules(rules)
    lines = ["E\\DE " + " ".join(f"{n:>2}" for n in SET_NAMES)]
    for name, row in zip(SET_NAMES, r, strict=True):
        lines.append(f"{name:>4} " + " ".join(f"{SET_NAMES[c]:>2}" for c in row))
    return "\n".join(lines) + "\n"


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
