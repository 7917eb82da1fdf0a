"""Settings of the MRAS's rotated adaptation error in low-speed regeneration.

The compiled half and the reasoning are in :mod:`imdrive.kernels.estimators.mras_stabilise`;
here the four settings of ``[mras]`` (per-unit of the machine) and the record fields they give.
"""

from __future__ import annotations

import math
from typing import Annotated

from imdrive.config.validation import Float, setting

RegenerationAngle = Annotated[
    Float,
    setting(
        "rotation of the MRAS's adaptation error where the stator frequency is against the "
        "speed (regeneration below the slip speed), e = Im{(λv - λ̂) λ̂* e^(-jφ)}, φ of the "
        "speed's sign: the loop of the MRAS, the field orientation and the speed controller "
        "is unstable there (kernels/estimators/mras_stabilise.py; 0: Schauder's error)",
        "deg",
        ge=0.0,
        lt=90.0,
    ),
]
RegenerationBand = Annotated[
    Float,
    setting(
        "the rotation ramps in over this much stator frequency, centred on 0: full where the "
        "stator frequency is half of it or more against the speed, none where it is half of it "
        "with the speed; per-unit of the machine's rated frequency",
        gt=0.0,
    ),
]
RegenerationSpeed = Annotated[
    Float,
    setting(
        "the rotation ramps in over this much speed estimate, per-unit of the machine's rated "
        "speed (so it is continuous through zero speed)",
        gt=0.0,
    ),
]


#: the rotation ramps in as the adjustable model's rotor flux builds up from this share of the
#: controller's flux reference at t = 0 to the next (``phi_lam_on``, ``phi_lam_full``)
FLUX_BUILT = (0.6, 0.9)


RegenerationGain = Annotated[
    Float,
    setting(
        "where the MRAS's error is rotated, scale it towards the unloaded MRAS's steady loop "
        "gain, 1 + g (φ/φmax) ((1 + x²)/(cos φ - x sin φ) - 1) at the slip x = ω_sl T̂2 "
        "(kernels/estimators/mras_stabilise.py regeneration_gain): 1 all of it, 0 none. It "
        "moves the linearised loop's regenerating pole into the left half-plane at 5 % speed "
        "but the rated regenerating step there still loses control (off by default)",
        ge=0.0,
        le=1.0,
    ),
]


def regeneration_params(mras, machine, psi0: float = 0.0) -> dict:
    """The ``MRAS_PARAMS`` fields of the rotation from ``[mras]`` and ``[machine]``.

    Parameters
    ----------
    mras : MrasSettings
    machine : Machine
    psi0 : float
        The controller's flux reference at t = 0, Wb: the rotation ramps in as the adjustable
        model's flux builds up to it (:data:`FLUX_BUILT`; 0: from the start).

    Returns
    -------
    dict
        ``phi_max`` (rad), ``phi_w_band`` (electrical rad/s), ``phi_w_speed`` (electrical
        rad/s), ``phi_lam_on`` and ``phi_lam_full`` (Wb), ``phi_gain`` (0 to 1).
    """
    from imdrive.config.machine import rated_point

    rp = rated_point(machine)
    w_m_rated = rp.speed_rpm * math.pi / 30.0
    return dict(
        phi_max=math.radians(mras.regeneration_angle_deg),
        phi_w_band=mras.regeneration_band_pu * rp.w_e_rad_s,
        phi_w_speed=mras.regeneration_speed_pu * w_m_rated * machine.pole_pairs,
        phi_lam_on=FLUX_BUILT[0] * psi0,
        phi_lam_full=FLUX_BUILT[1] * psi0,
        phi_gain=float(mras.regeneration_gain),
    )
