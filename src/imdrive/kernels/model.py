"""The controller's own machine model: the estimates its blocks share.

The field-oriented controller, the speed estimators and the flux models all use the
controller's *estimates* of the machine parameters (the "hats"), never the plant's. They are
state, not parameters: the rotor-resistance compensator adapts ``R2_hat`` online (and an
``R1_hat`` adaptation can update its own field the same way); every block reads the current
value, so a change acts from the next sample on.
"""

from numba import njit

from imdrive.kernels.records import f8, record_dtype

#: The controller's machine model (estimates), ohm and H.
MODEL_STATE = record_dtype(
    [
        ("R1_hat", f8),
        ("R2_hat", f8),
        ("Ll1_hat", f8),
        ("Ll2_hat", f8),
        ("M_hat", f8),
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
