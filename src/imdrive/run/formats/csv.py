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
        The file to write: a regular file or a link to one (written through), replaced
        atomically; a folder, a device or a FIFO is refused (:func:`imdrive._io.file_path_problem`).
    """
    from imdrive._io import output_file
    from imdrive.errors import ConfigError

    with output_file(path, lambda problem: ConfigError("path", problem)) as tmp:
        names = res.columns  # the path checked first: nothing is computed for a refused one
        data = np.column_stack([res.signals[n] for n in names])
        np.savetxt(tmp, data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")


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
