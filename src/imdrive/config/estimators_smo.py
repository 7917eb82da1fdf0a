"""Settings of the sliding-mode MRAS speed estimator (section ``[smo_mras]``), registered
with the others of :mod:`imdrive.config.estimators` (which imports this module)."""

from __future__ import annotations

import math
from typing import Annotated

from imdrive.config.registry import (
    EstimatorContext,
    EstimatorRecords,
    PeriodMeanCurrent,
    estimator_settings,
)
from imdrive.config.validation import Float, setting


@estimator_settings(
    "smo-mras",
    "smo_mras",
    log_units={"smo_sigma": ("rad", 1.0), "smo_u": ("rpm", 60.0 / (2.0 * math.pi))},
    flux_error=True,
    description="sliding-mode MRAS speed estimator",
)
class SmoMrasSettings:
    """Sliding-mode MRAS speed estimator (``[smo_mras]``, after Comanescu & Xu, IEEE Trans.
    Ind. Electron. 53(1), 2006; :mod:`imdrive.kernels.estimators.smo_mras`).

    The switching gain ``W`` (electrical rad/s) is the largest speed error the sliding mode
    holds, ``speed_error_pu`` times the machine's rated synchronous speed ``2 pi f_rated``;
    the equivalent control is the speed estimate, low-passed at ``bandwidth_Hz``; the boundary
    layer ``phi`` defaults to ``2 W Ts`` (a loop gain of 0.5 per period inside it).
    """

    wc_rad_s: Annotated[
        Float,
        setting(
            "cut-off of the 1/(s + ωc) replacement of the reference model's pure integrator "
            "(0: pure integrator), as [mras] wc_rad_s",
            "rad/s",
            ge=0.0,
        ),
    ] = 15.0
    bandwidth_Hz: Annotated[
        Float,
        setting(
            "bandwidth of the low-pass that extracts the equivalent control (the speed "
            "estimate follows the speed as a first-order lag of this bandwidth while sliding)",
            "Hz",
            gt=0.0,
        ),
    ] = 20.0
    speed_error_pu: Annotated[
        Float,
        setting(
            "largest speed error the sliding mode holds, per unit of the machine's rated "
            "synchronous speed: the switching gain W = speed_error_pu 2π f_rated (a larger "
            "error is slewed at 2π bandwidth_Hz W)",
            gt=0.0,
        ),
    ] = 0.1
    switching_gain_rad_s: Annotated[
        Float | None,
        setting(
            "switching gain W (electrical)",
            "rad/s",
            gt=0.0,
            default_doc="from speed_error_pu",
        ),
    ] = None
    boundary_layer_rad: Annotated[
        Float | None,
        setting(
            "boundary layer of the sliding variable (the flux angle error); 0: the pure sign "
            "function (the adjustable model's speed then chatters by ±W every period)",
            "rad",
            ge=0.0,
            default_doc="2 W Ts",
        ),
    ] = None

    period_mean_current: PeriodMeanCurrent = True

    def records(self, ctx: EstimatorContext) -> EstimatorRecords:
        """Switching gain, boundary layer and equivalent-control filter, each overridable.

        ``W = speed_error_pu 2 pi f_rated`` (electrical rad/s) or ``switching_gain_rad_s``;
        ``phi = 2 W Ts`` (rad) or ``boundary_layer_rad``; ``w_f = 2 pi bandwidth_Hz``
        (rad/s); the normalisation's floor ``(psi0 / 4)^2`` (Wb², as the MRAS's).

        Parameters
        ----------
        ctx : EstimatorContext
            The controller's model and the drive.

        Returns
        -------
        EstimatorRecords
        """
        w_rated = 2.0 * math.pi * ctx.scenario.machine.rated_frequency_Hz
        W = self.switching_gain_rad_s
        if W is None:
            W = self.speed_error_pu * w_rated
        phi = self.boundary_layer_rad if self.boundary_layer_rad is not None else 2.0 * W * ctx.Ts
        w_f = 2.0 * math.pi * self.bandwidth_Hz
        params = dict(
            wc=self.wc_rad_s,
            W=W,
            phi=phi,
            w_f=w_f,
            psi2_min=(0.25 * ctx.psi0) ** 2,
            bend=self.period_mean_current,
        )
        derived = {"smo_mras_W_rad_s": W, "smo_mras_phi_rad": phi, "smo_mras_w_f_rad_s": w_f}
        src = {
            "smo_mras_W_rad_s": (
                "smo_mras.switching_gain_rad_s"
                if self.switching_gain_rad_s is not None
                else "smo_mras.speed_error_pu"
            ),
            "smo_mras_phi_rad": "smo_mras.boundary_layer_rad",
            "smo_mras_w_f_rad_s": "smo_mras.bandwidth_Hz",
        }
        return EstimatorRecords(params, derived=derived, sources=src)
