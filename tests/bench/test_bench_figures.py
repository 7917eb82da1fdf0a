"""The benchmarks state figures as measured ranges with the machine (benchmarks/_measured.py)."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _measured():
    spec = importlib.util.spec_from_file_location("_measured", ROOT / "benchmarks" / "_measured.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_span_gives_the_range_the_median_and_the_number_of_runs():
    m = _measured()
    assert m.span([0.0030, 0.0025, 0.0041], "ms", 1e3) == "2.50–4.10 ms (median 3.00, 3 runs)"
    assert m.span([12.34], digits=1) == "12.3 s (1 run)"


def test_factor_span_goes_from_the_slowest_to_the_fastest_run():
    m = _measured()
    assert m.factor_span(3.0, [0.010, 0.008]) == "300–375×"
    assert m.factor_span(3.0, [0.010]) == "300×"


def test_machine_line_names_cpus_load_and_date():
    line = _measured().machine_line()
    pattern = r"machine: \d+ CPUs \(.+\), .+; load average .+; measured \d{4}-\d\d-\d\d$"
    assert re.match(pattern, line)


def test_every_timing_script_prints_the_machine_line():
    for script in ROOT.glob("benchmarks/bench_*.py"):
        if script.name in ("bench_gem.py", "bench_motulator.py"):
            continue  # run in the peers' venv, without imdrive; bench_batch reports them
        assert "machine_line()" in script.read_text(), f"{script.name} does not say the machine"
