"""``timeseries.parquet``: the signals in exact float64, zstd-compressed, units in the schema
metadata (``imdrive.units``, JSON)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from imdrive.run.columns import unit_of
from imdrive.run.formats import OutputFormat


def to_parquet(res, path) -> Path:
    """Write ``timeseries.parquet`` with the units in the schema metadata (``imdrive.units``).

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
    import pyarrow as pa
    import pyarrow.parquet as pq

    from imdrive._io import output_file
    from imdrive.errors import ConfigError

    with output_file(path, lambda problem: ConfigError("path", problem)) as tmp:
        table = pa.table({name: np.asarray(v) for name, v in res.signals.items()})
        meta = dict(table.schema.metadata or {})
        meta[b"imdrive.units"] = json.dumps({n: unit_of(n) for n in res.signals}).encode()
        # zstd: ~10 % smaller than snappy and reads faster (float noise compresses little)
        pq.write_table(table.replace_schema_metadata(meta), str(tmp), compression="zstd")
    return Path(path)


def read_parquet_units(path) -> dict[str, str]:
    """The units stored by :func:`to_parquet`.

    Parameters
    ----------
    path : str or pathlib.Path
        A ``timeseries.parquet``.

    Returns
    -------
    dict
        Column name -> unit.
    """
    import pyarrow.parquet as pq

    meta = pq.read_schema(str(path)).metadata or {}
    return json.loads(meta.get(b"imdrive.units", b"{}"))


FORMAT = OutputFormat(
    name="parquet",
    key="parquet",
    files=("timeseries.parquet",),
    write=lambda res, folder: to_parquet(res, folder / "timeseries.parquet"),
    description="every column in exact float64, zstd-compressed; units in the schema metadata "
    "(`imdrive.units`, JSON)",
    order=30,
)
