"""``timeseries.mat``: the signals for MATLAB, one double vector per column and a struct of
units."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from imdrive.run.columns import unit_of
from imdrive.run.formats import OutputFormat


def to_mat(res, path) -> Path:
    """Write ``timeseries.mat``: one double vector per column and a struct ``units``.

    MATLAB: ``d = load('timeseries.mat'); plot(d.time_s, d.speed_rpm); d.units.speed_rpm``.

    Parameters
    ----------
    res : SimulationResult
        The run.
    path : str or pathlib.Path
        The file to write: checked and replaced atomically (:func:`imdrive._io.output_file`).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    from scipy.io import savemat

    from imdrive._io import output_file
    from imdrive.errors import ConfigError

    with output_file(path, lambda problem: ConfigError("path", problem)) as tmp:
        data = {n: np.asarray(v, dtype=np.float64).reshape(-1, 1) for n, v in res.signals.items()}
        data["units"] = {name: unit_of(name) for name in res.signals}
        savemat(str(tmp), data, do_compression=True, oned_as="column")
    return Path(path)


FORMAT = OutputFormat(
    name="mat",
    key="mat",
    files=("timeseries.mat",),
    write=lambda res, folder: to_mat(res, folder / "timeseries.mat"),
    description="MATLAB file: one vector per column and a struct `units` (`d.units.speed_rpm`)",
    order=20,
)
