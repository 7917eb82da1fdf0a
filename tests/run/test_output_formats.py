"""The output formats' registry (imdrive.run.formats): one module per format, each tied to its
``[output]`` key, and the result folder's files read off it."""

from __future__ import annotations

import dataclasses

from imdrive.config.output import OutputSettings
from imdrive.run.files import RESULT_FILES, is_result_folder
from imdrive.run.formats import output_formats


def test_every_output_key_has_exactly_one_format():
    keys = [f.key for f in output_formats()]
    assert sorted(keys) == sorted(f.name for f in dataclasses.fields(OutputSettings))
    assert len(set(f.name for f in output_formats())) == len(keys)


def test_existing_file_names_are_kept():
    names = {n for f in output_formats() for n in f.files}
    assert names == {
        "timeseries.csv",
        "timeseries.mat",
        "timeseries.parquet",
        "report.html",
        "*.png",
        "recording.parquet",
        "recording.toml",
    }
    assert set(RESULT_FILES) == {
        "summary.json",
        "timeseries.csv",
        "report.html",
        "timeseries.mat",
        "timeseries.parquet",
        "recording.parquet",
        "recording.toml",
    }


def test_result_folder_recognises_every_format_and_nothing_else(tmp_path):
    for name in ("summary.json", "timeseries.csv", "speed.png", "timeseries.parquet"):
        (tmp_path / name).write_text("x")
    assert is_result_folder(tmp_path)
    (tmp_path / "notes.txt").write_text("mine")
    assert not is_result_folder(tmp_path)
