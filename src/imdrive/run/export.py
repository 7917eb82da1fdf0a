"""Exports of a run's signals beyond CSV: MATLAB ``.mat``, Parquet, xarray.

Every exported column keeps its unit: in the ``.mat`` file as a struct ``units`` (one field per
column), in Parquet as schema metadata (``imdrive.units``, JSON), in xarray as each variable's
``units`` attribute. The unit is the suffix of the column name (``speed_rpm`` -> ``rpm``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

#: unit suffixes of the exported columns, longest first so ``_rad_s`` wins over ``_s``
_SUFFIXES = ("rad_s", "ohm", "rpm", "Nm", "Wb", "rad", "A", "V", "C", "s")


def unit_of(column: str) -> str:
    """The unit a column's name ends with; ``"1"`` for a dimensionless column."""
    for u in _SUFFIXES:
        if column.endswith("_" + u):
            return "rad/s" if u == "rad_s" else u
    return "1"


def to_mat(res, path) -> Path:
    """Write ``timeseries.mat``: one double vector per column and a struct ``units``.

    MATLAB: ``d = load('timeseries.mat'); plot(d.time_s, d.speed_rpm); d.units.speed_rpm``.
    """
    from scipy.io import savemat

    data = {name: np.asarray(v, dtype=np.float64).reshape(-1, 1) for name, v in res.signals.items()}
    data["units"] = {name: unit_of(name) for name in res.signals}
    savemat(str(path), data, do_compression=True, oned_as="column")
    return Path(path)


def to_parquet(res, path) -> Path:
    """Write ``timeseries.parquet`` with the units in the schema metadata (``imdrive.units``)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({name: np.asarray(v) for name, v in res.signals.items()})
    meta = dict(table.schema.metadata or {})
    meta[b"imdrive.units"] = json.dumps({n: unit_of(n) for n in res.signals}).encode()
    # zstd: ~10 % smaller than the default snappy and reads faster (float noise compresses little)
    pq.write_table(table.replace_schema_metadata(meta), str(path), compression="zstd")
    return Path(path)


def read_parquet_units(path) -> dict[str, str]:
    """The units stored by :func:`to_parquet`."""
    import pyarrow.parquet as pq

    meta = pq.read_schema(str(path)).metadata or {}
    return json.loads(meta.get(b"imdrive.units", b"{}"))


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
