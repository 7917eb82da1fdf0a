"""Settings of the files ``imdrive run`` writes besides summary.json (section ``[output]``)."""

from __future__ import annotations

from typing import Annotated

from imdrive.config.validation import Bool, setting, settings


@settings("output")
class OutputSettings:
    """What ``imdrive run`` writes besides summary.json (``[output]``)."""

    figures: Annotated[
        Bool,
        setting(
            "write the PNG figures: speed.png, torque.png, currents.png, ... (report.html has "
            "the same plots, interactive; drawing the PNGs took half of a warm run)"
        ),
    ] = False
    csv: Annotated[
        Bool,
        setting(
            "write timeseries.csv (text, 9 significant digits; about 0.4 MB per simulated "
            "second of a vector drive at the default 1 kHz logging, 4 MB at log_every = 1: for "
            "long or full-rate runs prefer parquet = true, csv = false)"
        ),
    ] = True
    report: Annotated[
        Bool,
        setting(
            "write report.html: interactive linked plots, the summary and the scenario in one "
            "self-contained file that works offline"
        ),
    ] = True
    mat: Annotated[
        Bool, setting("write timeseries.mat (MATLAB; one vector per column, a units struct)")
    ] = False
    parquet: Annotated[
        Bool,
        setting(
            "write timeseries.parquet, the format for big runs: exact float64 (the CSV rounds "
            "to 9 digits), zstd-compressed, read about 2-3 times faster than the CSV and a third "
            "smaller (pandas.read_parquet; units in the schema metadata)"
        ),
    ] = False
    recording: Annotated[
        Bool,
        setting(
            "write recording.parquet and recording.toml: what the controller saw every control "
            "period (measured currents, DC-link voltage, commanded voltage, encoder speed, "
            "injection, and the context its speed estimator read), the input of imdrive "
            "replay (docs/replay.md)"
        ),
    ] = False
