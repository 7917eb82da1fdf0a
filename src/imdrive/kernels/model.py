"""The controller's own machine model: the estimates its blocks share.

The field-oriented controller, the speed estimators and the flux models all use the
controller's *estimates* of the machine parameters (the "hats"), never the plant's. They are
state, not parameters: the rotor-resistance compensator adapts ``R2_hat`` online (and an
``R1_hat`` adaptation can update its own field the same way); every block reads the current
value, so a change acts from the next sample on.
"""

from imdrive.kernels.jit import njit
from imdrive.kernels.records import b1, f8, i8, record_dtype

#: Most nodes of the controller's magnetising-curve table (``MODEL_STATE.sat_*``).
MODEL_TABLE_POINTS = 32

#: The controller's machine model (estimates), ohm and H.
MODEL_STATE = record_dtype(
    [
        ("R1_hat", f8),
        ("R2_hat", f8),
        ("Ll1_hat", f8),
        ("Ll2_hat", f8),
        ("M_hat", f8),  # the secant M_hat(psi_m_hat) when the table is on (sat_n > 0)
        # saturation-aware flux model (off: sat_n = 0, M_hat constant)
        ("sat_n", i8),  # nodes of the magnetising-curve table, 0: constant M_hat
        ("sat_psi", f8, (MODEL_TABLE_POINTS,)),  # magnetising flux at the nodes, Wb (increasing)
        ("sat_im", f8, (MODEL_TABLE_POINTS,)),  # magnetising current psi_m / Lm there, A
        ("sat_dim", f8, (MODEL_TABLE_POINTS,)),  # its slope d i_m / d psi_m there, 1/H
        ("sat_Lm0", f8),  # Lm at the first node, H (the curve below it: a line through 0)
        ("psi_m_hat", f8),  # the controller's magnetising-flux magnitude, Wb
        ("L_inc_hat", f8),  # the incremental inductance d psi_m / d i_m there, H
        # R1_hat holds a standstill identification (and with it the inverter's residual there)
        ("R1_id", b1),
        # the R1 the online R1 law's gate compares with the inverter's error (ohm): R1_hat(0),
        # then the identifications' (the standstill test, the inverter-error scale), never
        # the law's own (ifoc.r1_masked_by_inverter_error)
        ("R1_gate", f8),
        # the standstill test at two current levels (kernels/estimators/mras_standstill.py)
        ("dc_boost", f8),  # it asks for the flux reference times 1 + this
        ("dc_busy", b1),  # it holds the speed reference at zero
        ("t_hold", f8),  # the time the duty cycle (speed reference, load) was held, s
        ("dc_hold_max", f8),  # and the longest it may be, s
        ("u0_id", f8),  # the inverter's residual it identified along its current, V
        ("i_id", f8),  # at this current, A
        ("ie_new", b1),  # for the online inverter-error scale to start from (once)
    ]
)

#: Log fields of this block.
LOG_FIELDS = (
    "R2_hat",  # the rotor-resistance estimate, ohm
    "R1_hat",  # the stator-resistance estimate, ohm
)


@njit(cache=True)
def model_inductances(m):
    """``(M, L1, L2, sigma L1)`` of the model ``m``, H."""
    M = m.M_hat
    L1 = m.Ll1_hat + M
    L2 = m.Ll2_hat + M
    sigma_L1 = L1 - M * M / L2
    return M, L1, L2, sigma_L1


@njit(cache=True)
def _find_cell(x, xs, n):
    """The node ``k`` with ``xs[k] <= x < xs[k+1]`` (bisection; ``xs[0] <= x < xs[n-1]``)."""
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if xs[mid] <= x:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True)
def table_interp(x, xs, ys, n):
    """``y(x)`` linearly interpolated on the first ``n`` nodes ``xs`` (increasing), held at
    the end values outside them; and the slope ``dy/dx`` there (0 outside)."""
    if x <= xs[0]:
        return ys[0], 0.0
    if x >= xs[n - 1]:
        return ys[n - 1], 0.0
    lo = _find_cell(x, xs, n)
    dy = ys[lo + 1] - ys[lo]
    # a flat cell's slope is dy itself (+-0, as dy/dx with dx > 0): no division
    slope = dy if dy == 0.0 else dy / (xs[lo + 1] - xs[lo])
    return ys[lo] + slope * (x - xs[lo]), slope


@njit(cache=True)
def _hermite_cell(m, psi_m):
    """The cell ``k`` of the table holding ``|psi_m|`` (Wb, strictly inside the nodes), its
    width ``h`` (Wb), the position ``t`` in it and ``t^2``, ``t^3``."""
    xs = m.sat_psi
    k = _find_cell(psi_m, xs, m.sat_n)
    h = xs[k + 1] - xs[k]
    t = (psi_m - xs[k]) / h
    t2 = t * t
    return k, h, t, t2, t2 * t


@njit(cache=True)
def _hermite_current(m, k, h, t, t2, t3):
    """The magnetising current ``i_m`` (A) of cell ``k`` at ``t`` (cubic Hermite)."""
    d0 = h * m.sat_dim[k]
    d1 = h * m.sat_dim[k + 1]
    i_m = (2 * t3 - 3 * t2 + 1) * m.sat_im[k] + (t3 - 2 * t2 + t) * d0
    i_m += (3 * t2 - 2 * t3) * m.sat_im[k + 1]
    return i_m + (t3 - t2) * d1


@njit(cache=True)
def magnetising_inductances(m, psi_m):
    """The model's secant and incremental magnetising inductances at ``|psi_m|`` (Wb), H.

    The magnetising current ``i_m(psi_m)`` is a cubic Hermite interpolation of the table's
    nodes (``sat_im``) with their slopes (``sat_dim``, three-point differences limited to keep
    the curve monotone: :func:`imdrive.config.controller_model.magnetising_table`), so the
    secant ``Lm = psi_m / i_m`` is exact at the nodes and the incremental inductance
    ``L_inc = 1 / (d i_m / d psi_m)`` is continuous. Below the first node the curve is the line
    of slope ``1/sat_Lm0`` through the origin; past the last it continues with the last slope.
    """
    n = m.sat_n
    xs = m.sat_psi
    if psi_m <= xs[0]:
        return m.sat_Lm0, m.sat_Lm0
    if psi_m >= xs[n - 1]:
        d = m.sat_dim[n - 1]
        i_m = m.sat_im[n - 1] + d * (psi_m - xs[n - 1])
        return psi_m / i_m, 1.0 / d
    k, h, t, t2, t3 = _hermite_cell(m, psi_m)
    i_m = _hermite_current(m, k, h, t, t2, t3)
    y0 = m.sat_im[k]
    y1 = m.sat_im[k + 1]
    d0 = h * m.sat_dim[k]
    d1 = h * m.sat_dim[k + 1]
    di = ((6 * t2 - 6 * t) * (y0 - y1) + (3 * t2 - 4 * t + 1) * d0 + (3 * t2 - 2 * t) * d1) / h
    return psi_m / i_m, 1.0 / di


@njit(cache=True)
def magnetising_secant(m, psi_m):
    """The secant ``Lm`` of :func:`magnetising_inductances` alone (H), the same number:
    without the incremental inductance's derivative and its two divisions."""
    n = m.sat_n
    xs = m.sat_psi
    if psi_m <= xs[0]:
        return m.sat_Lm0
    if psi_m >= xs[n - 1]:
        return psi_m / (m.sat_im[n - 1] + m.sat_dim[n - 1] * (psi_m - xs[n - 1]))
    k, h, t, t2, t3 = _hermite_cell(m, psi_m)
    return psi_m / _hermite_current(m, k, h, t, t2, t3)


@njit(cache=True)
def update_magnetising(m, psi_r_hat, i_dq):
    """Set ``m.M_hat`` to the secant ``Lm`` at the magnetising flux the controller believes.

    In the rotor-flux frame (``psi_r_hat`` real, Wb; stator current ``i_dq``, A) the
    magnetising flux is ``psi_m = (M/L2)(psi_r + Ll2 i_s)`` (from ``psi_r = M i_s + L2 i_r``
    and ``psi_m = M (i_s + i_r)``, secant inductances at ``|psi_m|``: exact at every instant
    for a curve through the origin). One fixed-point step per period, from the last ``M_hat``;
    in steady state ``psi_m = psi_r + j (M Ll2/L2) i_q``. No-op without a table.
    """
    if m.sat_n == 0:
        return
    M = m.M_hat
    k = M / (m.Ll2_hat + M)
    pm_d = k * (psi_r_hat + m.Ll2_hat * i_dq.real)
    pm_q = k * m.Ll2_hat * i_dq.imag
    psi_m = (pm_d * pm_d + pm_q * pm_q) ** 0.5
    Lm, L_inc = magnetising_inductances(m, psi_m)
    m.M_hat = Lm
    m.psi_m_hat = psi_m
    m.L_inc_hat = L_inc


@njit(cache=True)
def reference_magnetising(m, psi_ref, i_q):
    """The secant ``Lm`` the flux reference ``psi_ref`` (Wb) needs in steady state at the
    torque current ``i_q`` (A): at ``|psi_m| = |psi_ref + j (M Ll2/L2) i_q|``; ``M_hat``
    without a table."""
    if m.sat_n == 0:
        return m.M_hat
    M = m.M_hat
    pm_q = M * m.Ll2_hat / (m.Ll2_hat + M) * i_q
    return magnetising_secant(m, (psi_ref * psi_ref + pm_q * pm_q) ** 0.5)


@njit(cache=True)
def incremental_L2(m):
    """The rotor inductance a small flux variation sees, ``Ll2 + L_inc`` (H): the secant
    ``L2 = Ll2 + M_hat`` without a table (constant model)."""
    if m.sat_n == 0:
        return m.Ll2_hat + m.M_hat
    return m.Ll2_hat + m.L_inc_hat
