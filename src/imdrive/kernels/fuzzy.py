"""Compiled parts of the fuzzy compensator: quantisation (Tables I/II), the run-time Table III
lookup, and the inner loops of table compilation and rule fitting (see :mod:`imdrive.fuzzy`)."""

from __future__ import annotations

import numpy as np

from imdrive.kernels.jit import njit

# Tables I/II: upper bounds of the positive levels 1 ... 5 of the scaled input (the paper's
# thresholds 0.25, 1, 2, 3, 4, 5, in units of 1e-6 Wb before scaling)
THRESHOLDS = np.array([0.25, 1.0, 2.0, 3.0, 4.0, 5.0], dtype=np.float64)
THRESHOLDS.flags.writeable = False

# the first _N_SINGLE moves of the rule-fitting search change one rule, the rest two
_N_SINGLE = 49


@njit(cache=True)
def quantize(x: float) -> int:
    """Quantise a scaled input to its level −6 … 6 (Tables I/II).

    Every interval is open below and closed above, as the paper prints them: level 0 is
    ``−0.25 < x ≤ 0.25``; with ``t = THRESHOLDS`` (0-based), level k = 1 … 5 is
    ``t[k−1] < x ≤ t[k]`` and level −k is ``−t[k] < x ≤ −t[k−1]``; level 6 is ``x > 5`` and
    level −6 is ``x ≤ −5``. So the map is *not* odd at the thresholds:
    ``quantize(0.25) = 0`` but ``quantize(-0.25) = -1``.

    Parameters
    ----------
    x : float
        Input already multiplied by its scaling gain (dimensionless).

    Returns
    -------
    int
        Level in −6 … 6; NaN maps to 0 so a bad sample cannot move the estimate.
    """
    if x != x:  # NaN
        return 0
    n = 0
    if x > 0.0:
        for t in THRESHOLDS:  # positive side: count thresholds strictly below x
            if x > t:
                n += 1
        return n
    for t in THRESHOLDS:  # negative side: count thresholds with x <= -t
        if x <= -t:
            n += 1
    return -n


@njit(cache=True)
def _cell(i, j, rules, membership, peaks, method):
    """CR at E index ``i``, DE index ``j`` (level + 6); NaN if no rule fires."""
    if method == 0:
        # eq. (12) literally: every fired rule contributes its grade times its set's value,
        # so two rules with the same output set both count
        num = 0.0
        den = 0.0
        for a in range(7):
            ua = membership[i, a]
            if ua <= 0.0:
                continue
            for b in range(7):
                u = min(ua, membership[j, b])  # eq. (11)
                if u > 0.0:
                    num += u * peaks[rules[a, b]]
                    den += u
        if den <= 0.0:
            return np.nan
        return num / den
    # Mamdani: clip each fired rule's output set at its grade, aggregate by max over U, then
    # take the centre of gravity of the aggregated set over the 13 discrete levels
    agg = np.zeros(13)
    for a in range(7):
        ua = membership[i, a]
        if ua <= 0.0:
            continue
        for b in range(7):
            u = min(ua, membership[j, b])
            if u > 0.0:
                c = rules[a, b]
                for y in range(13):
                    g = min(u, membership[y, c])
                    if g > agg[y]:
                        agg[y] = g
    num = 0.0
    den = 0.0
    for y in range(13):
        num += (y - 6) * agg[y]
        den += agg[y]
    if den <= 0.0:
        return np.nan
    return num / den


@njit(cache=True, entry=True)
def _compile(rules, membership, peaks, method):
    out = np.empty((13, 13))
    for i in range(13):
        for j in range(13):
            out[i, j] = _cell(i, j, rules, membership, peaks, method)
    return out


@njit(cache=True)
def _round1(v):
    # scalar twin of round_level (round to 9 decimals, then half away from zero)
    v = np.round(v * 1e9) / 1e9
    if v >= 0.0:
        return np.floor(v + 0.5)
    return -np.floor(-v + 0.5)


@njit(cache=True)
def _cell_cost(v, target):
    # (differs, |diff|, squared unrounded residual) of one cell; NaN (nothing fired) counts as 0
    if v != v:
        v = 0.0
    r = _round1(v)
    d = abs(r - target)
    return (1.0 if d > 0.0 else 0.0), d, (v - target) ** 2


@njit(cache=True, entry=True)
def _violations(rules):
    # total size of the steps where the output set decreases as E or DE grows
    v = 0
    for a in range(7):
        for b in range(7):
            if a < 6 and rules[a, b] > rules[a + 1, b]:
                v += rules[a, b] - rules[a + 1, b]
            if b < 6 and rules[a, b] > rules[a, b + 1]:
                v += rules[a, b] - rules[a, b + 1]
    return v


@njit(cache=True)
def _better(d, best):
    # lexicographic comparison of cost-change vectors; the last key (a float residual) with a
    # tolerance so that rounding noise cannot make the search cycle
    for k in range(d.size - 1):
        if d[k] != best[k]:
            return d[k] < best[k]
    return d[-1] < best[-1] - 1e-9


@njit(cache=True)
def _delta(rules, mask, vals, target, membership, peaks, method, reg, viol0, out, newvals):
    """Cost change of the current (modified) ``rules`` vs the state ``vals`` / ``viol0``.

    Only the cells in ``mask`` are recomputed. ``out`` receives the change of the cost vector
    (monotonicity violations if ``reg == 2``, differing cells, Σ|diff|, violations if
    ``reg == 1``, Σ residual²); the recomputed cell values go to ``newvals``.
    """
    for k in range(5):
        out[k] = 0.0
    for i in range(13):
        for j in range(13):
            if mask[i, j]:
                v = _cell(i, j, rules, membership, peaks, method)
                newvals[i, j] = v
                n0, n1, n2 = _cell_cost(v, target[i, j])
                o0, o1, o2 = _cell_cost(vals[i, j], target[i, j])
                out[1] += n0 - o0
                out[2] += n1 - o1
                out[4] += n2 - o2
    if reg > 0:
        out[0 if reg == 2 else 3] = _violations(rules) - viol0


@njit(cache=True)
def _try_move(rules, a, b, c, e, fire, mask, vals, viol, target, membership, peaks, method, reg):
    """Give rules (a, b) and (c, e) their best values; True if that lowered the cost.

    ``(c, e) == (a, b)`` is a single-rule move. For a pair, only values where both rules change
    are tried (single moves cover the rest). A rule (a, b) only changes the cells where set a
    fires on E and set b fires on DE, so only those cells (``mask``) are rescored.
    """
    single = a == c and b == e
    for i in range(13):
        for j in range(13):
            mask[i, j] = (fire[i, a] and fire[j, b]) or (fire[i, c] and fire[j, e])
    o1 = rules[a, b]
    o2 = rules[c, e]
    bv1 = o1
    bv2 = o2
    d = np.zeros(5)
    best = np.zeros(5)
    newvals = np.empty((13, 13))
    bestvals = np.empty((13, 13))  # cell values of the best move so far (no rescoring needed)
    for v1 in range(7):
        if v1 == o1:
            continue
        for v2 in range(7):
            if single:
                if v2 > 0:
                    break
            elif v2 == o2:
                continue
            rules[a, b] = v1
            if not single:
                rules[c, e] = v2
            _delta(rules, mask, vals, target, membership, peaks, method, reg, viol, d, newvals)
            if _better(d, best):
                for k in range(5):
                    best[k] = d[k]
                for i in range(13):  # explicit loops: slice assignment is slow to compile
                    for j in range(13):
                        bestvals[i, j] = newvals[i, j]
                bv1 = v1
                bv2 = rules[c, e]
    rules[a, b] = bv1
    rules[c, e] = bv2
    if bv1 == o1:
        return False
    for i in range(13):
        for j in range(13):
            if mask[i, j]:
                vals[i, j] = bestvals[i, j]
    return True


@njit(cache=True, entry=True)
def _descend(rules, target, membership, peaks, method, reg, moves):
    """Local search in place on ``rules``: single-rule moves, then pair moves (``moves``).

    Single moves are swept until none helps, then pair moves; any success returns to single
    moves. Moves are tried in a fixed order and taken on strict improvement of the cost vector
    (see :func:`_delta`): deterministic, and it terminates because every move lowers the cost.
    """
    vals = _compile(rules, membership, peaks, method)
    fire = np.zeros((13, 7), dtype=np.bool_)  # set c fires at level index i
    for i in range(13):
        for c in range(7):
            fire[i, c] = membership[i, c] > 0.0
    mask = np.zeros((13, 13), dtype=np.bool_)
    lo, hi = 0, _N_SINGLE
    while True:
        improved = False
        for k in range(lo, hi):
            a, b, c, e = moves[k, 0], moves[k, 1], moves[k, 2], moves[k, 3]
            viol = _violations(rules)
            ok = _try_move(
                rules, a, b, c, e, fire, mask, vals, viol, target, membership, peaks, method, reg
            )
            improved = improved or ok
        if improved:
            lo, hi = 0, _N_SINGLE
        elif lo == 0:
            lo, hi = _N_SINGLE, moves.shape[0]
        else:
            return rules


@njit(cache=True)
def lookup(table, e_scaled, de_scaled):
    """Table III lookup for the drive kernel: ``table[quantize(E) + 6, quantize(DE) + 6]``.

    Parameters
    ----------
    table : float64[13, 13]
        Lookup table, rows E, columns DE (levels −6 … 6).
    e_scaled, de_scaled : float
        E and DE already multiplied by their scaling gains.

    Returns
    -------
    float
        Output level CR; the caller scales it to a resistance change.
    """
    return table[quantize(e_scaled) + 6, quantize(de_scaled) + 6]
