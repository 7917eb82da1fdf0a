"""How the benchmarks state a figure: a measured range, with the machine and the date.

A single number from a shared machine says little (the same command ran twice as long on
another machine of the same kind), so every script prints the range over its repeated runs
with the median and the number of runs (:func:`span`, :func:`factor_span`), and one line saying
what machine measured it, how loaded it was and when (:func:`machine_line`).
"""

from __future__ import annotations

import os
import platform
import statistics
import time


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine_line() -> str:
    """One line: CPUs, processor, system, Python, load average now, today's date."""
    try:
        load = f"load average {os.getloadavg()[0]:.1f} at start"
    except OSError:
        load = "load average unknown"
    return (
        f"machine: {os.cpu_count()} CPUs ({_cpu_model()}), {platform.system()} "
        f"{platform.release()}, Python {platform.python_version()}; {load}; "
        f"measured {time.strftime('%Y-%m-%d')}"
    )


def span(values, unit: str = "s", scale: float = 1.0, digits: int = 2) -> str:
    """``"lo–hi unit (median m, n runs)"`` of ``values`` times ``scale``.

    Parameters
    ----------
    values : sequence of float
        The measured times, s (or any quantity, with ``unit`` after scaling).
    unit : str
        Unit printed after the scaled values.
    scale : float
        Factor applied before printing (1e3 for s -> ms).
    digits : int
        Decimals printed.

    Returns
    -------
    str
        The range, median and number of runs.
    """
    v = sorted(x * scale for x in values)
    if len(v) == 1:
        return f"{v[0]:.{digits}f} {unit} (1 run)"
    return (
        f"{v[0]:.{digits}f}–{v[-1]:.{digits}f} {unit} "
        f"(median {statistics.median(v):.{digits}f}, {len(v)} runs)"
    )


def factor_span(simulated_s: float, times_s) -> str:
    """Real-time factor range ``"lo–hi×"``: simulated seconds per wall (or CPU) second.

    Parameters
    ----------
    simulated_s : float
        Simulated time of one run, s.
    times_s : sequence of float
        The measured times of the runs, s.

    Returns
    -------
    str
        Slowest to fastest run.
    """
    lo, hi = simulated_s / max(times_s), simulated_s / min(times_s)
    return f"{lo:.0f}×" if len(times_s) == 1 else f"{lo:.0f}–{hi:.0f}×"
