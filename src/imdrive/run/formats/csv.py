"""``timeseries.csv``: the signals as text, one column per signal, units in the header names."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imdrive.run.formats import OutputFormat


def to_csv(res, path) -> None:
    """Write the signals as CSV (header = column names with units), 9 significant digits.

    Parameters
    ----------
    res : SimulationResult
        The run.
    path : str or pathlib.Path
        The file to write.
    """
    names = res.columns
    data = np.column_stack([res.signals[n] for n in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")


def _write(res, folder: Path) -> None:
    res.to_csv(folder / "timeseries.csv")  # the method, so a patched one is used


FORMAT = OutputFormat(
    name="csv",
    key="csv",
    files=("timeseries.csv",),
    write=_write,
    description="every column as text (9 significant digits), the header is the column names",
    order=10,
)
