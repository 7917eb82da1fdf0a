"""Fuzzy-logic rotor-resistance compensator: the paper's tables, inference, rule fitting (§4).

The paper's compensator (Fig. 3) quantises the d-axis flux error ``E = e_d0`` and its change
``DE`` into 13 levels −6 … 6 (Tables I and II), infers the change of the resistance estimate
``CR`` from 49 rules ``if E is A and DE is B then CR is C`` with min-inference (eq. 11) and
centre-of-gravity defuzzification (eq. 12), and stores the result as a 13 × 13 lookup table
(Table III). The drive kernel only ever sees that table, through :func:`lookup`.

The package is split by what a module needs, each importing only those to its left::

    tables  <-  inference  <-  fit

* :mod:`imdrive.fuzzy.tables` — the paper's data (:data:`THRESHOLDS`, :data:`MEMBERSHIP`,
  :data:`PAPER_TABLE_III`, ...), the fitted rule bases :data:`FITTED_RULES` and
  :data:`FITTED_RULES_MONOTONE` (pasted as data), and helpers to compare and print tables;
* :mod:`imdrive.fuzzy.inference` — :func:`infer`, :func:`compile_table` in two variants
  (``"rules"``: eq. (12) read literally, the default; ``"universe"``: textbook Mamdani), and
  :func:`fuzzy_table`, the table a drive uses;
* :mod:`imdrive.fuzzy.fit` — :func:`fit_rules_to_table`, the search for the unprinted rule base.

The compiled parts (:func:`quantize`, :func:`lookup` and the inner loops) live in
:mod:`imdrive.kernels.fuzzy`. Every name is re-exported here, so ``imdrive.fuzzy.X`` keeps
working for all the names listed in ``__all__``.

Levels are integers −6 … 6 and are stored at array index ``level + 6``; fuzzy sets are indexed
0 … 6 in the order of :data:`SET_NAMES`.
"""

from __future__ import annotations

from imdrive.fuzzy.fit import DEFAULT_FIT_STARTS, FitResult, fit_rules_to_table
from imdrive.fuzzy.inference import (
    METHODS,
    compile_table,
    compile_table_float,
    default_rules,
    fuzzy_table,
    infer,
    quantize_array,
    round_level,
)
from imdrive.fuzzy.tables import (
    FITTED_RULES,
    FITTED_RULES_MONOTONE,
    LEVELS,
    MEMBERSHIP,
    PAPER_TABLE_III,
    SET_NAMES,
    SET_PEAKS,
    THRESHOLDS,
    format_rules,
    format_table,
    table_diff,
    table_score,
)
from imdrive.kernels.fuzzy import lookup, quantize

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
