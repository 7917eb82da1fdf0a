"""``bench-estimators`` input (issue 40, class 11): an open-loop base, an empty or unknown
estimator list, empty or non-finite speeds and loads are bad input (exit 2, one line naming
the flag) refused before any run, and nothing is written: no empty --out folder, no 1-byte
estimators.csv. The API refuses the same."""

from __future__ import annotations

import io
from contextlib import redirect_stderr, redirect_stdout

import pytest

from imdrive.bench.report import bench_estimators
from imdrive.cli import main
from imdrive.errors import ConfigError


@pytest.mark.parametrize(
    "flag, value",
    [
        ("--base", "free-acceleration"),
        ("--estimators", ","),
        ("--estimators", ""),
        ("--estimators", "nosuch"),
        ("--estimators", "mras,nosuch"),
        ("--speeds", ","),
        ("--speeds", "nan"),
        ("--loads", "inf"),
        ("--loads", "x"),
        ("--speeds", "1e300"),
        ("--base", "nosuch-preset"),
    ],
)
def test_refused_lists_exit_2_and_leave_nothing(tmp_path, monkeypatch, flag, value):
    import imdrive.run.batch as batch

    def _no_run(*a, **k):
        raise AssertionError("a drive was simulated")

    monkeypatch.setattr(batch, "simulate_batch", _no_run)
    out = tmp_path / "bench"
    err = io.StringIO()
    with redirect_stderr(err), redirect_stdout(io.StringIO()):
        rc = main(["bench-estimators", "--quick", "--out", str(out), f"{flag}={value}"])
    lines = [x for x in err.getvalue().strip().splitlines() if x.startswith("imdrive: error:")]
    assert rc == 2, err.getvalue()
    assert len(lines) == 1 and "Traceback" not in err.getvalue()
    field = lines[0].split(": ")[2]
    assert field in (flag, "scenario") or field.startswith("control."), lines[0]
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_the_api_refuses_before_writing(tmp_path):
    out = tmp_path / "b"
    with pytest.raises(ConfigError, match="^estimators: is empty"):
        bench_estimators(out, estimators=[])
    with pytest.raises(ConfigError, match="^estimators: no configuration 'nosuch'"):
        bench_estimators(out, estimators=["nosuch"])
    with pytest.raises(ConfigError, match="^drives: 'free-acceleration' runs open-loop"):
        bench_estimators(out, quick=True, drives={"fa": "free-acceleration"})
    assert list(tmp_path.iterdir()) == []
