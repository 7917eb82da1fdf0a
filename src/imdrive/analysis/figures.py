"""Figures of the steady-state analysis, drawn with matplotlib's object API.

matplotlib is imported inside each function, so ``import imdrive.analysis`` stays light.
"""

from __future__ import annotations

import numpy as np

from imdrive.analysis.foc import detuning_speed_error_rpm
from imdrive.config.machine import MachineParams

__all__ = ["plot_speed_error_vs_R2"]


def plot_speed_error_vs_R2(machine: MachineParams, speed_rpm: float, loads_Nm, ratios, ax=None):
    """Plot the sensorless drive's steady-state speed error against ``R2_hat / R2``.

    Parameters
    ----------
    machine : MachineParams
    speed_rpm : float
        Speed reference, mechanical rpm.
    loads_Nm : iterable of float
        Load torques, N m; one curve each.
    ratios : array_like
        Values of ``R2_hat / R2`` on the horizontal axis.
    ax : matplotlib.axes.Axes, optional
        Axes to draw into; by default a new :class:`matplotlib.figure.Figure` is created (no pyplot
        global state, safe with the Agg backend).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from imdrive._figure import DisplayFigure as Figure

    if ax is None:
        fig = Figure(figsize=(6.0, 4.0), layout="constrained")
        ax = fig.add_subplot()
    else:
        fig = ax.figure
    r = np.asarray(ratios, dtype=float)
    for load in loads_Nm:
        err = detuning_speed_error_rpm(machine, speed_rpm, load, r)
        ax.plot(r, np.atleast_1d(err), marker=".", label=f"{load:g} N m")
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.axvline(1.0, color="0.5", lw=0.8, ls=":")
    ax.set_xlabel(r"$\hat R_2 / R_2$")
    ax.set_ylabel("speed error, actual − reference (rpm)")
    ax.set_title(f"MRAS-sensorless IFOC, $n^*$ = {speed_rpm:g} rpm")
    ax.grid(True, alpha=0.3)
    ax.legend(title="load")
    return fig
