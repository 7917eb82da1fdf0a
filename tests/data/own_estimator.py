"""A speed estimator written outside the package, as a user would (the plug-in example).

Flux-angle speed estimator: the rotor flux from the voltage model (Park et al., eq. 1, with
Schauder's 1/(s + wc) in place of the integrator), its angle differentiated, less the slip
frequency the controller's model gives for the measured current (Ohtani, Takada & Tanaka,
IEEE Trans. Ind. Appl. 28(1), 1992, speed from the flux rotation less the slip)::

    w_r_hat = LPF( d angle(lam_v)/dt - (R2_hat M / L2) Im(conj(lam_v) i) / |lam_v|^2 )

It has no flux error for the R2 compensator (returns ``0j``). Open loop in the speed: no
adaptation loop to tune, but it inherits the voltage model's weakness at low stator
frequency (the 1/(s + wc) filter's phase and gain error below ``wc``). Measured on the paper's
machine (sensorless preset, 3 s ramps): within 2 rpm at 800-1200 rpm, 0-12 N m; at 400 rpm
and no load the speed loop limit-cycles (estimate 150-200 rpm off for seconds). At a
magnetised standstill ``v = R1 i`` and the filter forgets the flux within ``1/wc`` (0.2 s), so
a steep ramp started after the drive's premagnetisation finds no flux angle to differentiate
(0 -> 800 rpm in 0.5 s after 0.26 s at standstill: the estimate 1626 rpm off, control lost;
started with the flux build-up: 44 rpm off at most). An example of the plug-in mechanism,
not a recommended estimator.
"""

from __future__ import annotations

import cmath
import math
from typing import Annotated

import numpy as np
from numba import njit

from imdrive.run.estimators import (
    EstimatorRecords,
    Float,
    ReducedState,
    c16,
    estimator_settings,
    f8,
    record_dtype,
    register_kernel,
    setting,
    to_frame,
)

FLUX_ANGLE_PARAMS = record_dtype(
    [
        ("wc", f8),  # voltage-model filter cut-off, rad/s
        ("a_f", f8),  # speed filter: exp(-w_f Ts)
    ]
)
FLUX_ANGLE_STATE = record_dtype(
    [
        ("lam_ab", c16),  # voltage-model rotor flux, Wb
        ("w_raw", f8),  # unfiltered speed of the last period, electrical rad/s
        ("w_r_hat", f8),  # filtered speed estimate, electrical rad/s
    ]
)


@njit(cache=True)
def flux_angle_step(p, m, s, inp):
    """One period: voltage model, flux-angle rate less slip, low-pass. Returns (w, 0j)."""
    M = m.M_hat
    L2 = m.Ll2_hat + M
    L1 = m.Ll1_hat + M
    sigma_L1 = L1 - M * M / L2
    Ts = inp.Ts
    i_mean = 0.5 * (inp.i_ab + inp.i_prev_ab)
    d_lam = (L2 / M) * (Ts * (inp.v_ab - m.R1_hat * i_mean) - sigma_L1 * (inp.i_ab - inp.i_prev_ab))
    lam_old = s.lam_ab
    lam = math.exp(-p.wc * Ts) * lam_old + d_lam
    s.lam_ab = lam
    mag2 = abs(lam) ** 2
    if mag2 > 1e-6 and abs(lam_old) > 1e-3:
        w_psi = cmath.phase(lam * lam_old.conjugate()) / Ts
        w_sl = m.R2_hat * M / L2 * (lam.conjugate() * inp.i_ab).imag / mag2
        s.w_raw = w_psi - w_sl
    s.w_r_hat = p.a_f * s.w_r_hat + (1.0 - p.a_f) * s.w_raw
    return s.w_r_hat, 0j


@njit(cache=True)
def log_flux_angle(row, p, s, n_p):
    """Its own log fields: the voltage-model flux."""
    row.lam_fa_alpha = s.lam_ab.real
    row.lam_fa_beta = s.lam_ab.imag


@njit(cache=True)
def reduce_flux_angle(p, s, c, z, k):
    """Its states for the stability maps, in the controller's frame at ``c = (cos, sin)``."""
    z[k], z[k + 1] = to_frame(c, s.lam_ab)
    z[k + 2] = s.w_raw
    z[k + 3] = s.w_r_hat


@njit(cache=True)
def restore_flux_angle(z, k, s):
    """And back (the frame angle 0)."""
    s.lam_ab = complex(z[k], z[k + 1])
    s.w_raw = z[k + 2]
    s.w_r_hat = z[k + 3]


def steady_flux_angle(c, p, I, w_e, w_r_hat):
    """Its states at rest: the filtered voltage model's flux, the speed on the estimate."""
    L2, M = c["L2_hat"], c["M_hat"]
    emf = c["v"] - c["R1_hat"] * I - 1j * w_e * c["sL1_hat"] * I
    lam = (L2 / M) * emf / (1j * w_e + p["wc"])
    return np.column_stack([lam.real, lam.imag, w_r_hat, w_r_hat])


KERNEL = register_kernel(
    "flux-angle",
    FLUX_ANGLE_PARAMS,
    FLUX_ANGLE_STATE,
    flux_angle_step,
    log_fields=("lam_fa_alpha", "lam_fa_beta"),
    log=log_flux_angle,
    reduced=ReducedState(
        ("lam_d", "lam_q", "w_raw", "w_r_hat"),
        (0.1, 0.1, 1.0, 1.0),
        reduce_flux_angle,
        restore_flux_angle,
        steady_flux_angle,
    ),
)


@estimator_settings(
    "flux-angle",
    log_units={"lam_fa_alpha": ("Wb", 1.0), "lam_fa_beta": ("Wb", 1.0)},
    description="flux-angle speed estimator (voltage model, angle rate less slip)",
)
class FluxAngleSettings:
    """Flux-angle speed estimator (``[plugins.settings.flux-angle]``)."""

    wc_rad_s: Annotated[Float, setting("voltage-model filter cut-off", "rad/s", gt=0.0)] = 5.0
    filter_Hz: Annotated[Float, setting("speed low-pass bandwidth", "Hz", gt=0.0)] = 30.0

    def records(self, ctx):
        """The filter constants (no gain to design)."""
        a_f = math.exp(-2.0 * math.pi * self.filter_Hz * ctx.Ts)
        return EstimatorRecords(
            params={"wc": self.wc_rad_s, "a_f": a_f}, derived={"flux_angle_a_f": a_f}
        )
