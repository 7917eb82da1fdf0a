"""Errors: bad input (exit code 2 in the CLI) and environment failures (exit code 4)."""


class _FieldRule:
    """A field and the rule it broke (or looks wrong by), as one line ``field: rule``."""

    def __init__(self, field: str, rule: str):
        self.field = _one_line(field)
        self.rule = _one_line(rule)
        super().__init__(f"{self.field}: {self.rule}")

    def __reduce__(self):
        # pickled with its two arguments: raised in a worker process (a user's
        # ProcessPoolExecutor) it reaches the parent as itself, not as a BrokenProcessPool
        return (type(self), (self.field, self.rule))


class ConfigError(_FieldRule, ValueError):
    """A scenario or parameter value broke a rule.

    Parameters
    ----------
    field : str
        Dotted path of the offending field, e.g. ``machine.R1_ohm``.
    rule : str
        The rule it broke, e.g. ``must be > 0``.
    """


class ConfigWarning(_FieldRule, UserWarning):
    """A suspicious but possible input (a rated slip above 10 %, a power factor of 0.3).

    The run goes on; the command line prints it as one line ``imdrive: warning: field: rule``.

    Parameters
    ----------
    field : str
        Dotted path of the field, e.g. ``machine.rated_speed_rpm``.
    rule : str
        What looks wrong, e.g. ``rated slip 14 % is above 10 %``.
    """


def _one_line(text: str) -> str:
    """``text`` with control characters escaped (a key may hold a newline): one line."""
    text = str(text)
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode() for c in text)


class SimulationDiverged(RuntimeError):
    """A run whose states left physical bounds (NaN, inf, or beyond the set limits).

    Parameters
    ----------
    time_s : float
        Simulated time at which the run diverged, s.
    signal : str
        What diverged, e.g. ``stator current``.
    result : SimulationResult, optional
        The partial result up to the divergence.
    """

    def __init__(self, time_s: float, signal: str, result=None):
        self.time_s = time_s
        self.signal = signal
        self.result = result
        super().__init__(f"simulation diverged at t = {time_s:.6g} s: {signal}")

    def __reduce__(self):
        # pickled with its arguments (a worker process's error reaches the parent as itself)
        return (type(self), (self.time_s, self.signal, self.result))


class EnvironmentFailure(RuntimeError):
    """The environment failed a run that was valid: I/O, full disk, permissions, memory, cluster.

    The CLI prints the message on one line and exits with code 4; what was written stays, and
    looks incomplete (no ``summary.json``, a manifest that does not say ``complete``).

    Parameters
    ----------
    cause : str
        One line naming the cause, e.g. ``cannot write out/x/summary.json: No space left on
        device``.
    """

    def __init__(self, cause: str):
        self.cause = cause
        super().__init__(cause)


def describe_os_error(exc: OSError, doing: str = "") -> str:
    """One line for an :class:`OSError`: what was being done, the path, the system's reason.

    Parameters
    ----------
    exc : OSError
        The error.
    doing : str
        What failed, e.g. ``"cannot write"``; default ``"I/O error on"``.

    Returns
    -------
    str
        E.g. ``cannot write out/run/summary.json: No space left on device (ENOSPC)``.
    """
    import errno

    reason = exc.strerror or str(exc) or type(exc).__name__
    code = errno.errorcode.get(exc.errno or -1)
    if code:
        reason = f"{reason} ({code})"
    if exc.filename is None:
        return f"{doing or 'I/O error'}: {reason}"
    return f"{doing or 'I/O error on'} {exc.filename}: {reason}"


def check_argument(value, types, name: str, what: str):
    """``value`` if it is an instance of ``types``, else a :class:`ConfigError` naming the
    argument: a public entry point refuses a wrong argument at once, in the package's own
    error, instead of failing later with a ``TypeError`` or ``AttributeError``.

    Parameters
    ----------
    value : object
        The argument.
    types : type or tuple of type
        What it must be (a bool is never taken for an int).
    name : str
        The argument's name, e.g. ``"scenario"``.
    what : str
        What to give, e.g. ``"a Scenario (Scenario.read(...))"``.

    Returns
    -------
    object
        ``value``.
    """
    if not isinstance(value, types) or (isinstance(value, bool) and bool not in _tuple(types)):
        raise ConfigError(name, f"must be {what}, got {type(value).__name__}")
    return value


def check_number(value, name: str, lo: float | None = None) -> float:
    """``value`` as a float if it is a finite real number (``>= lo`` when given), else a
    :class:`ConfigError` naming the argument: a NaN or infinite argument would otherwise come
    back as a silent NaN result or an overflow deep inside.

    Parameters
    ----------
    value : object
        The argument.
    name : str
        The argument's name, e.g. ``"window_s"``.
    lo : float, optional
        The smallest value allowed, in the argument's own unit (s for ``window_s``).

    Returns
    -------
    float
        ``value``.
    """
    import math
    import numbers

    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if not ok or not math.isfinite(value) or (lo is not None and value < lo):
        rule = "a finite number" + (f" >= {lo:g}" if lo is not None else "")
        raise ConfigError(name, f"must be {rule}, got {value!r}")
    return float(value)


def _tuple(types) -> tuple:
    return types if isinstance(types, tuple) else (types,)
