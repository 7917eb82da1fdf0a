"""Settings of the integration and of the logging (section ``[simulation]``), and the default
logging decimation.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import model_validator

from imdrive.config.validation import Float, Int, setting, settings
from imdrive.errors import ConfigError

#: slowest default logging rate, Hz (see :func:`default_log_every`)
DEFAULT_LOG_RATE_HZ = 1000.0


def default_log_every(Ts_s: float) -> int:
    """The default logging decimation: the most control periods per logged row that keep the
    log at >= :data:`DEFAULT_LOG_RATE_HZ` (10 at Ts = 100 µs; 1 for Ts >= 1 ms).

    Parameters
    ----------
    Ts_s : float
        Control period, s.

    Returns
    -------
    int
        ``max(1, floor(1 / (DEFAULT_LOG_RATE_HZ Ts_s)))``, at most 2e9.
    """
    # the small tolerance keeps 1e-3 / 1e-4 (= 9.999999999999998) at 10
    n = int((1.0 / (DEFAULT_LOG_RATE_HZ * Ts_s)) * (1.0 + 1e-9))
    return min(max(n, 1), 2_000_000_000)


@settings("simulation")
class SimulationSettings:
    """Integration and logging (``[simulation]``)."""

    t_end_s: Annotated[Float, setting("run length", "s", gt=0.0)] = 1.0
    tracking_windows: Annotated[
        Int | None,
        setting(
            "run length in R2 tracking's decision windows after compensator.t_on_s, instead "
            "of t_end_s (<= 1e6): the window holds whole injection periods, and the "
            "injection's frequency follows the rotor's corner (injection.frequency_pu), so "
            "the tracking time follows the machine. injection-robust states 20 (14 s on "
            "Table IV, as before); with its 14 s R̂2 had not moved on Krause 500 and 2250 hp "
            "and the 3.3 kV machine (windows of 4.5-9.2 s), with 20 windows all seven "
            "library machines end within 0.001 %",
            ge=1,
            le=1_000_000,
        ),
    ] = None
    Ts_s: Annotated[Float, setting("control period (sampling and PWM period)", "s", gt=0.0)] = (
        100e-6
    )
    substeps: Annotated[
        Int,
        setting(
            "RK4 steps of the plant per control period (<= 1000: beyond, the step is far below "
            "any time constant of the machine and the run only gets slower)",
            ge=1,
            le=1000,
        ),
    ] = 1
    log_every: Annotated[
        Int | None,
        setting(
            "logging decimation: one row of timeseries every this many control periods "
            "(<= 2e9, the most periods a run may have; 1: every period). The default keeps "
            "logging at >= 1 kHz, which resolves everything up to the current loop (its "
            "bandwidth is a few hundred Hz) and the stator frequency; report.html is "
            "min/max-decimated anyway. It is fixed when the scenario is read (summary.json "
            "records the number); Scenario.with_overrides derives the default again for a new "
            "Ts_s",
            ge=1,
            le=2_000_000_000,
            default_doc="max(1, floor(1 ms / Ts_s)): 10 at the default Ts_s = 100 µs",
        ),
    ] = None
    divergence_current_A: Annotated[
        Float | None,
        setting(
            "current magnitude that stops a diverging run",
            "A",
            gt=0.0,
            derived=True,
        ),
    ] = None
    divergence_speed_rpm: Annotated[
        Float | None,
        setting(
            "speed magnitude that stops a diverging run",
            "rpm",
            gt=0.0,
            derived=True,
        ),
    ] = None
    lost_control_rpm: Annotated[
        Float | None,
        setting(
            "loss of control: the actual speed departs from its reference by more than this "
            "(vector control, free speed; 0: not checked)",
            "rpm",
            ge=0.0,
            derived=True,
        ),
    ] = None
    lost_control_s: Annotated[
        Float,
        setting("... for at least this long without interruption", "s", gt=0.0),
    ] = 1.0

    @model_validator(mode="after")
    def _period_fits_run(self):
        if self.Ts_s > self.t_end_s:
            raise ConfigError("Ts_s", "must be <= simulation.t_end_s")
        if self.t_end_s / self.Ts_s > 2e9:
            raise ConfigError("Ts_s", "gives more than 2e9 periods")
        if self.log_every is None:
            # frozen dataclass: set once here, so every consumer sees an int; the mark lets
            # Scenario.with_overrides derive it again when Ts_s changes
            object.__setattr__(self, "log_every", default_log_every(self.Ts_s))
            object.__setattr__(self, "_log_every_auto", True)
        return self

    @property
    def n_steps(self) -> int:
        return int(round(self.t_end_s / self.Ts_s))
