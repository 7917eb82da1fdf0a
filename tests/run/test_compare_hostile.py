"""``compare`` on a corrupt or foreign result folder (issue 40, class 6): every one is bad
input, exit 2 with one line naming the file, never exit 5 and nothing written; the API
refuses misuse with ConfigError."""

from __future__ import annotations

import io
import os
import shutil
from contextlib import redirect_stderr, redirect_stdout

import pytest

from imdrive import Scenario, simulate
from imdrive.cli import main
from imdrive.errors import ConfigError
from imdrive.run.compare import compare


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """A short result with both time-series formats."""
    folder = tmp_path_factory.mktemp("good") / "r"
    res = simulate(Scenario.read("sensorless", ["simulation.t_end_s=0.02"]))
    res.save(folder, formats=["csv", "parquet"])
    return folder


def _summary_text(good):
    return (good / "summary.json").read_text()


CASES = {
    "malformed JSON": ("summary.json", lambda d, g: (d / "summary.json").write_text("{no")),
    "nested JSON": (
        "summary.json",
        lambda d, g: (d / "summary.json").write_text("[" * 100_000 + "]" * 100_000),
    ),
    "UTF-16 JSON": (
        "summary.json",
        lambda d, g: (d / "summary.json").write_bytes(_summary_text(g).encode("utf-16")),
    ),
    "a JSON list": ("summary.json", lambda d, g: (d / "summary.json").write_text("[1, 2]")),
    "a FIFO summary": (
        "summary.json",
        lambda d, g: ((d / "summary.json").unlink(), os.mkfifo(d / "summary.json")),
    ),
    "a link to /dev/zero": (
        "summary.json",
        lambda d, g: ((d / "summary.json").unlink(), (d / "summary.json").symlink_to("/dev/zero")),
    ),
    "empty CSV": ("timeseries.csv", lambda d, g: (d / "timeseries.csv").write_text("")),
    "header-only CSV": (
        "timeseries.csv",
        lambda d, g: (d / "timeseries.csv").write_text(
            (g / "timeseries.csv").read_text().splitlines()[0] + "\n"
        ),
    ),
    "text-valued CSV": (
        "timeseries.csv",
        lambda d, g: (d / "timeseries.csv").write_text("time_s,speed_rpm\nabc,def\n"),
    ),
    "CSV without time_s": (
        "timeseries.csv",
        lambda d, g: (d / "timeseries.csv").write_text("a,b\n1,2\n"),
    ),
    "binary CSV": (
        "timeseries.csv",
        lambda d, g: (d / "timeseries.csv").write_bytes(b"\xff\xfe\x00\x01garbage"),
    ),
    "a FIFO CSV": (
        "timeseries.csv",
        lambda d, g: ((d / "timeseries.csv").unlink(), os.mkfifo(d / "timeseries.csv")),
    ),
    "empty Parquet": (
        "timeseries.parquet",
        lambda d, g: (d / "timeseries.parquet").write_bytes(b""),
    ),
    "corrupt Parquet": (
        "timeseries.parquet",
        lambda d, g: (d / "timeseries.parquet").write_bytes(b"PAR1garbagegarbagePAR1"),
    ),
    "truncated Parquet": (
        "timeseries.parquet",
        lambda d, g: (d / "timeseries.parquet").write_bytes(
            (g / "timeseries.parquet").read_bytes()[:200]
        ),
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_compare_refuses_a_corrupt_folder_naming_the_file(good, tmp_path, case):
    name, spoil = CASES[case]
    bad = tmp_path / "bad"
    shutil.copytree(good, bad)
    if name != "timeseries.parquet":  # the CSV is read when there is no Parquet
        (bad / "timeseries.parquet").unlink()
    spoil(bad, good)
    out = tmp_path / "cmp"
    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()):
        rc = main(["compare", str(good), str(bad), "--out", str(out)])
    lines = [x for x in err.getvalue().strip().splitlines() if x.startswith("imdrive: error:")]
    assert rc == 2, err.getvalue()
    assert len(lines) == 1 and "Traceback" not in err.getvalue()
    assert str(bad / name) in lines[0], lines[0]
    assert not out.exists()


def test_compare_api_misuse_is_a_config_error(good):
    with pytest.raises(ConfigError, match="^runs:"):
        compare(None)
    with pytest.raises(ConfigError, match="^labels: 1 names for 2 runs"):
        compare([good, good], labels=["a"])
    with pytest.raises(ConfigError, match="^run:"):
        compare([5])
    assert list(compare([good, good]).metrics.columns) == ["r", "r (2)"]  # the good one compares
