"""Gain design: formulas that turn bandwidths into controller and estimator gains."""

from imdrive.design.gains import default_current_gains, default_mras_gains, default_speed_gains

__all__ = ["default_current_gains", "default_mras_gains", "default_speed_gains"]
