"""The paper's fuzzy data (Tables I-III) and helpers to compare and print tables.

Everything here is data or a pure function of data; nothing compiles a table. The inference
that turns a rule base into a table lives in :mod:`imdrive.fuzzy.inference`, the search for the
unprinted rule base in :mod:`imdrive.fuzzy.fit`. Dependency direction inside the package:
``tables`` <- ``inference`` <- ``fit`` (the fitted rule bases are pasted here as data, so this
module never needs the search that produced them).

Levels are integers −6 … 6 and are stored at array index ``level + 6``; fuzzy sets are indexed
0 … 6 in the order of :data:`SET_NAMES`.
"""

from __future__ import annotations

import numpy as np

from imdrive.errors import ConfigError
from imdrive.kernels.fuzzy import THRESHOLDS

__all__ = [
    "THRESHOLDS",
    "LEVELS",
    "SET_NAMES",
    "SET_PEAKS",
    "MEMBERSHIP",
    "PAPER_TABLE_III",
    "FITTED_RULES",
    "FITTED_RULES_MONOTONE",
    "table_score",
    "table_diff",
    "format_table",
    "format_rules",
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

for _a in (THRESHOLDS, LEVELS, SET_PEAKS, MEMBERSHIP, PAPER_TABLE_III):
    _a.flags.writeable = False  # shared module constants: a stray in-place edit must fail loudly

# --------------------------------------------------------------------------------------------
# Rule bases reconstructed from Table III (the paper does not print its rules)

#: Rule base fitted to Table III by :func:`~imdrive.fuzzy.fit.fit_rules_to_table` (all defaults:
#: method "rules", regularity "tiebreak"), pasted here as data so importing costs nothing.
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
#: table is exactly antisymmetric. See :func:`~imdrive.fuzzy.fit.fit_rules_to_table` for why it
#: may be the better reconstruction.
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
# Validating rule bases and membership grades


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


# --------------------------------------------------------------------------------------------
# Comparing and printing tables


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
