"""Errors raised for bad input. The CLI turns them into one-line messages and exit code 2."""


class ConfigError(ValueError):
    """A scenario or parameter value broke a rule.

    Parameters
    ----------
    field : str
        Dotted path of the offending field, e.g. ``machine.R1_ohm``.
    rule : str
        The rule it broke, e.g. ``must be > 0``.
    """

    def __init__(self, field: str, rule: str):
        self.field = field
        self.rule = rule
        super().__init__(f"{field}: {rule}")


class SimulationDiverged(RuntimeError):
    """A run whose states left physical bounds (NaN, inf, or beyond the set limits)."""

    def __init__(self, time_s: float, signal: str, result=None):
        self.time_s = time_s
        self.signal = signal
        self.result = result
        super().__init__(f"simulation diverged at t = {time_s:.6g} s: {signal}")
