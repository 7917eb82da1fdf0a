"""Settings of the model-based R2 law (section ``[kalman]``, ``compensator.step_law =
"kalman"``): a Kalman filter on R2 and its drift rate (:mod:`imdrive.kernels.r2_kalman`)."""

from __future__ import annotations

from typing import Annotated

from imdrive.config.r2_laws import r2_law
from imdrive.config.validation import Float, setting, settings


@r2_law("kalman", "kalman", "model-based R2 law: a Kalman filter on R2 and its drift rate")
@settings("kalman")
class KalmanLawSettings:
    """The model-based R2 law (``[kalman]``): every setting relative to R2, so one tuning
    holds on every machine.

    Each decision window's detected flux error is divided by its analytic sensitivity to R2
    (the injection's in-phase flux response,
    :func:`~imdrive.kernels.sensitivity.in_phase_sensitivity`), which measures the relative
    R2 error; a two-state Kalman filter (R2 and its drift rate) weighs that measurement
    against its prediction. The step size, the ramp following and the damping are its gains;
    no other setting shapes them.
    """

    noise_pu: Annotated[
        Float,
        setting(
            "standard deviation of one decision window's measured relative R2 error: the "
            "filter's measurement noise. Smaller follows faster and passes more of the "
            "detection's ripple into R̂2",
            gt=0.0,
            le=1.0,
        ),
    ] = 0.03
    drift_pu: Annotated[
        Float,
        setting(
            "how fast R2's drift rate may change: the white acceleration noise's standard "
            "density, in per-unit of R̂2(0) per second per √s. Larger follows a heating ramp "
            "sooner and holds a constant R2 less still. 0.02 was best of 0.002-0.04 on the "
            "envelope sweep's switching-bridge cells (R̂2(0) 0.7-1.3 R2): at 1.5-2 x rated "
            "speed with a +20 % ramp within goal 40 of 48 (0.002-0.01: 36-38); at 0.1-2 x "
            "rated speed with and without it "
            "66 of 72 (0.01: 65, 0.04: 63)",
            "1/s^1.5",
            gt=0.0,
            le=1.0,
        ),
    ] = 0.02
    prior_pu: Annotated[
        Float,
        setting(
            "standard deviation of R̂2(0)'s relative error: how far the first windows may move "
            "R̂2 (0.3: a cold or hot rotor, R2 0.7-1.3 times its estimate)",
            gt=0.0,
            le=2.0,
        ),
    ] = 0.3
