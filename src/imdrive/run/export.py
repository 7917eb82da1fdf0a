"""Exports of a run's signals beyond CSV: MATLAB ``.mat``, Parquet, xarray.

Every exported column keeps its unit: in the ``.mat`` file as a struct ``units`` (one field per
column), in Parquet as schema metadata (``imdrive.units``, JSON), in xarray as each variable's
``units`` attribute. The unit is the suffix of the column name (``speed_rpm`` -> ``rpm``).
The MAT and Parquet writers live with their output format (:mod:`imdrive.run.formats`).
"""

from __future__ import annotations

import numpy as np

from imdrive.run.columns import unit_of
from imdrive.run.formats.mat import to_mat
from imdrive.run.formats.parquet import read_parquet_units, to_parquet

__all__ = ["read_parquet_units", "to_mat", "to_parquet", "to_xarray", "unit_of"]


def to_xarray(res):
    """The signals as an ``xarray.Dataset`` over ``time_s`` with units as attributes.

    Needs the optional dependency xarray (``pip install xarray``).
    """
    try:
        import xarray as xr
    except ImportError as exc:  # an optional dependency: say how to get it
        raise ImportError("to_xarray needs xarray: pip install xarray") from exc
    t = np.asarray(res.signals["time_s"])
    data = {
        name: ("time_s", np.asarray(v), {"units": unit_of(name)})
        for name, v in res.signals.items()
        if name != "time_s"
    }
    return xr.Dataset(data, coords={"time_s": ("time_s", t, {"units": "s"})})
