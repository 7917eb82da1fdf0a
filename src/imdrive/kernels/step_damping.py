"""Overshoot damping of the adaptive step law's table levels (``p.damp``).

Outside its fine band the adaptive law steps R2_hat by ``G_CR`` times the paper's table
level (:func:`imdrive.kernels.compensator.compensator_update`). The level grows with the
detected error, so the step per % of R2 error, the loop's gain per decision, is set by the
detection's sensitivity at the operating point. Where that sensitivity is higher than the
table was drawn for, the steps overshoot: a table-level step carries R2_hat across the fine
band to a table level of the other sign, and the loop settles into a limit cycle instead of
the fine band (measured on Table IV at 20 rpm, rated motoring torque, from R2_hat(0) =
1.3 R2, the injection at its third frequency: R2_hat swinging -10.5 ... +10.8 % for the
last 15 s of a 40 s run, speed +-3.7 rpm; with G_CR halved it converged to +0.03 %).

The damping measures the overshoot instead of modelling the sensitivity: a table-level step
whose sign is opposite to the previous table-level step's halves the steps that follow (at
most :data:`DAMP_MAX_HALVINGS` times); one of the same sign doubles them back (at most to
the table's own). A start far from R2 (every step of one sign) and a heating ramp (likewise)
are not slowed; it is the sign-alternation rule of Riedmiller & Braun's resilient
propagation (Rprop, Proc. IEEE Int. Conf. Neural Networks, 1993) applied to the table's
step.
"""

from __future__ import annotations

from numba import njit

#: the most the table's steps are halved (to a quarter)
DAMP_MAX_HALVINGS = 2.0
#: the halvings one table-level step of the same sign as the last one takes back
DAMP_RECOVERY = 0.25


@njit(cache=True)
def table_step_factor(s, cr):
    """The factor on a table-level step of level ``cr`` (updates ``s.damp_n``, ``s.big_sign``).

    Parameters
    ----------
    s : COMPENSATOR_STATE record
        ``damp_n``: the halvings in force; ``big_sign``: the sign of the last table-level
        step (0: none yet).
    cr : float
        The table's output level of this decision, outside the fine band.

    Returns
    -------
    float
        ``0.5 ** damp_n`` after this step's sign is compared with the last one's.
    """
    if cr == 0.0:
        return 0.5**s.damp_n
    sign = 1.0 if cr > 0.0 else -1.0
    if s.big_sign * sign < 0.0:
        s.damp_n = min(s.damp_n + 1.0, DAMP_MAX_HALVINGS)
    elif s.big_sign * sign > 0.0:
        s.damp_n = max(s.damp_n - DAMP_RECOVERY, 0.0)
    s.big_sign = sign
    return 0.5**s.damp_n
