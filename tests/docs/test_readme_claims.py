"""README.md's numbers agree with their sources (issue 39: it said 2.25 MW for a library whose
largest machine is 1.68 MW, 2.5-3.5 s for an R2 convergence the generated table gives as
1.5-2.5 s, and 170-380x real time where benchmarks/README.md says 167-380x)."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd

from imdrive.config.machine import machine_preset, machine_presets

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text(encoding="utf-8")
PAPER = (ROOT / "docs" / "paper-reproduction.md").read_text(encoding="utf-8")
COMPENSATION = pd.read_csv(ROOT / "docs" / "figures" / "compensation.csv")


def _flat(text: str) -> str:
    return re.sub(r"\s+", " ", text)


def _range(text: str, pattern: str) -> tuple[float, float]:
    m = re.search(pattern, _flat(text))
    assert m, pattern
    return float(m.group(1)), float(m.group(2))


def test_the_real_time_factor_is_the_benchmarks():
    bench = (ROOT / "benchmarks" / "README.md").read_text(encoding="utf-8")
    source = _range(bench, r"`sensorless` preset \(3 s\), kernel on one core \| (\d+)–(\d+)×")
    assert _range(README, r"one drive runs (\d+)–(\d+) times faster than real time") == source


def test_the_r2_convergence_is_the_generated_tables():
    """The time to 2 % of the injection presets, from the compensator's switch-on, as
    ``imdrive paper`` wrote it (docs/figures/compensation.csv)."""
    inj = COMPENSATION[COMPENSATION["compensator"] == "injection"]["time_to_tolerance_s"]
    source = (inj.min(), inj.max())
    assert len(inj) == 4 and inj.notna().all()
    pattern = r"within 2 % (?:of R2 )?in (\d+(?:\.\d+)?)–(\d+(?:\.\d+)?) s of its switch-on"
    assert _range(README, pattern) == source
    assert _range(PAPER, pattern) == source


def test_the_library_span_is_the_machine_library():
    powers = [machine_preset(n).rated_power_W for n in machine_presets()]
    m = re.search(r"\((\w+) published machines from ([\d.]+) kW to ([\d.]+) MW", _flat(README))
    assert m
    words = "zero one two three four five six seven eight nine ten eleven twelve".split()
    assert m.group(1) in (str(len(powers)), words[len(powers)])
    assert float(m.group(2)) == round(min(powers) / 1e3, 1)
    assert float(m.group(3)) == round(max(powers) / 1e6, 2)


def test_the_first_commands_status_line_is_explained_with_its_numbers():
    """The line after README's first command quotes what ``imdrive run paper-fig5`` prints
    (its R2_hat error and speed error, from the generated table of the same runs)."""
    row = COMPENSATION.set_index("preset").loc["paper-fig5"]
    first = README.split("imdrive run paper-fig5", 1)[1][:800]
    flat = _flat(first)
    assert f"R2_hat off by {row['R2_hat_final_error_pct']:.0f} %" in flat
    assert f"speed error {row['speed_error_after_rpm']:.1f} rpm" in flat
    assert "the paper's finding, not a broken install" in flat
