"""Running drives: scenario -> kernel arrays (build), one drive, many drives, results."""

from imdrive.run.batch import BatchResult, simulate_batch
from imdrive.run.result import SimulationResult
from imdrive.run.simulate import build_arrays, simulate

__all__ = ["BatchResult", "SimulationResult", "build_arrays", "simulate", "simulate_batch"]
