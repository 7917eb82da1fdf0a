"""``recording.parquet`` and ``recording.toml``: what the controller saw every control period,
the input of ``imdrive replay`` (:mod:`imdrive.run.recording`)."""

from __future__ import annotations

from imdrive.run.formats import OutputFormat


def _write(res, folder) -> None:
    from imdrive.run.recording import write_recording

    write_recording(res, folder)


FORMAT = OutputFormat(
    name="recording",
    key="recording",
    files=("recording.parquet", "recording.toml"),
    write=_write,
    description="what the controller saw every control period (measured currents, DC-link "
    "voltage, commanded voltage, encoder speed, injection, and the context its estimator "
    "read), zstd Parquet (floats byte-stream split) with units in the schema metadata, and "
    "recording.toml (units, sample period, estimator, the scenario): the input of "
    "`imdrive replay`",
    order=35,
)
