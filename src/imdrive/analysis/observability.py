"""How far an R1_hat error moves the R2 estimate at an operating point: R2's observability
near zero stator frequency.

Both R2 detections of the drive (the MRAS's flux error ``e_dq0``; the flux detector's for the
other estimators, :mod:`imdrive.kernels.flux_detector`) compare a voltage model of the rotor
flux, which integrates ``v - R1_hat i``, with a current model, which uses R2_hat. In the
steady state at the stator frequency ``w_e`` (controller's frame) the voltage model's rotor
flux is

    lam_v = (L2/M) ((v - R1_hat i) / (j w_e) - sigma L1 i),

so an error ``dR1 = d1 R1`` moves it by ``-(L2/M) d1 R1 i / (j w_e)``: a share

    g d1,     g = (L2/M) R1 |i_s| / (|w_e| psi_r)                                   (1)

of the rotor flux. The R2 law reads the models' disagreement as an R2 error, so to first order
R2_hat moves by about ``g`` per unit of R1_hat's error. At zero stator frequency ``g`` is
infinite: neither R2 nor the speed can be told from R1 there (Holtz, "Sensorless control of
induction motor drives", Proc. IEEE 90(8), 2002), and the injection does not change this.

Measured (docs/machine-envelope.md, ``zero-frequency-R1``: ``injection-robust`` regenerating
the rated torque with R1_hat held 1 % off): on the MRAS drive R2_hat moved by 3.3, 1.8 and 0.4
% at 0.5, 1 and 2 Hz on Table IV, where (1) gives 3.5, 1.75 and 0.87; 7.2, 5.3 and 2.3 % on the
Aalto 2.2 kW machine against 8.2, 4.1 and 2.1. On the adaptive observer's drive, whose
detection runs its current model at the observer's speed (which R1 moves too), it moved by
far more below 2 Hz (84 % at 1 Hz on Krause 500 hp, where (1) gives 1.3), and near 0 Hz the
observer lost control in 9 of the 24 runs below 1 Hz.
"""

from __future__ import annotations

import math

#: R1_hat's relative error a drive should assume when it judges R2_hat (``g`` times it against
#: the R2 tolerance): a resistance measured at a known winding temperature and corrected to
#: the operating one is good to about 1 % (IEEE Std 112-2017, 5.4); the standstill test leaves
#: the ideal drive 0.02 % off, but through a run the stator heats by tens of kelvins (copper
#: 0.39 %/K), which only an online R1 law follows.
R1_UNCERTAINTY = 0.01


def r2_r1_sensitivity(
    R1_ohm: float, M_H: float, L2_H: float, i_s_A: float, w_e_rad_s: float, psi_r_Wb: float
) -> float:
    """R2_hat's relative change per relative R1_hat error at an operating point, eq. (1) of
    the module docstring: ``g = (L2/M) R1 |i_s| / (|w_e| psi_r)`` (dimensionless).

    Parameters
    ----------
    R1_ohm : float
        Stator resistance (the drive's R1_hat), ohm.
    M_H, L2_H : float
        Magnetising and rotor inductances, H.
    i_s_A : float
        Stator current magnitude (peak, the controller's dq frame), A.
    w_e_rad_s : float
        Stator frequency, electrical rad/s (its sign does not matter).
    psi_r_Wb : float
        Rotor flux magnitude, Wb.

    Returns
    -------
    float
        ``g``; ``inf`` at zero stator frequency, NaN for a non-positive flux.
    """
    if not psi_r_Wb > 0.0:
        return math.nan
    num = (L2_H / M_H) * R1_ohm * abs(i_s_A)
    w = abs(w_e_rad_s)
    return num / (w * psi_r_Wb) if w > 0.0 else math.inf
