"""Identification accuracy over random plants, and its table in docs/commissioning.md.

Each plant: a library machine (``paper-table-iv`` or ``aalto-2.2kw``) with R1, R2, Ll1, Ll2,
M and J each scaled by a random factor in [0.7, 1.3] (independently), on the realistic drive of
the ``sensorless-realistic`` preset (switching bridge, 2 us dead time, 1 V drops, a
one-period delay, current sensors with gain, offset, noise and a 12-bit ADC, saturation).

``python -m imdrive.commission.accuracy [--plants N] [--check]`` regenerates (or checks) the
table between the markers of docs/commissioning.md.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

MACHINES = ("paper-table-iv", "aalto-2.2kw")
QUANTITIES = ("R1_ohm", "R2_ohm", "sigma_L1_H", "L1_H", "J_kgm2", "Lm_H", "u_err_V")
#: The goals, % (``u_err_V``, the inverter-error table's plateau, has none).
GOALS = {"R1_ohm": 3, "R2_ohm": 5, "sigma_L1_H": 10, "L1_H": 5, "J_kgm2": 10, "Lm_H": 3}
DOC = Path(__file__).resolve().parents[3] / "docs" / "commissioning.md"
CSV = DOC.parent / "data" / "commissioning-accuracy.csv"
BEGIN, END = "<!-- accuracy table: begin -->", "<!-- accuracy table: end -->"


def random_plant(k: int, seed: int = 0):
    """The ``k``-th random plant's scenario."""
    from imdrive.config.machine import preset_table
    from imdrive.config.scenario import Scenario

    rng = np.random.default_rng([seed, k])
    name = MACHINES[k % len(MACHINES)]
    base = preset_table(name)
    sets = [f'machine.preset="{name}"']
    for key in ("R1_ohm", "R2_ohm", "Ll1_H", "Ll2_H", "M_H", "J_kgm2"):
        sets.append(f"machine.{key}={base[key] * rng.uniform(0.7, 1.3)!r}")
    sets.append(f"sensor.seed={k + 1}")
    return Scenario.read("sensorless-realistic", sets)


def accuracy_rows(n: int, seed: int = 0) -> list[dict]:
    """One row per plant: its machine and the relative error of each quantity (or the test
    that failed)."""
    from imdrive.commission import CommissioningFailed
    from imdrive.commission.identify import identify

    rows = []
    for k in range(n):
        sc = random_plant(k, seed)
        row = {"plant": k, "machine": MACHINES[k % len(MACHINES)], "failed": ""}
        try:
            err = identify(sc).relative_error
            row.update({q: err[q] for q in QUANTITIES})
        except CommissioningFailed as exc:
            row["failed"] = f"{exc.test}: {exc.reason}"
        rows.append(row)
    return rows


def table(rows: list[dict]) -> str:
    """The Markdown table: worst and median |relative error| of each quantity, %."""
    ok = [r for r in rows if not r["failed"]]
    lines = [
        f"{len(ok)} of {len(rows)} random plants identified ({len(rows) - len(ok)} failed a test).",
        "",
        "| quantity | goal | median | worst |",
        "|---|---|---|---|",
    ]
    for q in QUANTITIES:
        e = np.abs([float(r[q]) for r in ok]) * 100.0
        goal = f"{GOALS[q]} %" if q in GOALS else "-"
        lines.append(f"| {q} | {goal} | {np.median(e):.2f} % | {np.max(e):.2f} % |")
    return "\n".join(lines)


def page(text: str, rows: list[dict]) -> str:
    """``text`` with the table between the markers replaced."""
    a, b = text.index(BEGIN) + len(BEGIN), text.index(END)
    return text[:a] + "\n" + table(rows) + "\n" + text[b:]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m imdrive.commission.accuracy")
    ap.add_argument("--plants", type=int, default=20)
    ap.add_argument("--check", action="store_true", help="check the page against the CSV")
    ap.add_argument("--path", default=str(DOC))
    args = ap.parse_args(argv)
    import pandas as pd

    path = Path(args.path)
    text = path.read_text(encoding="utf-8")
    if args.check:
        rows = pd.read_csv(CSV, keep_default_na=False).to_dict("records")
        if text != page(text, rows):
            print(f"{path} is stale: run python -m imdrive.commission.accuracy", file=sys.stderr)
            return 1
        return 0
    rows = accuracy_rows(args.plants)
    CSV.parent.mkdir(parents=True, exist_ok=True)
    pd.DataFrame(rows).to_csv(CSV, index=False)
    path.write_text(page(text, rows), encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
