"""Regenerate ``preset_baseline.json``: every preset's summary metrics and a hash of its signals.

Run from the repository root only when a change of the numerics is *intended* (say so in the
commit message)::

    python tests/data/make_preset_baseline.py

``tests/test_preset_baseline.py`` compares every preset against this file bit for bit: a
refactor of the layout (issue 14) must not change a single bit of any result.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "preset_baseline.json"


def fingerprint(res, columns) -> dict:
    """Status, final values, energies, compensation metrics and a SHA-256 of the columns."""
    h = hashlib.sha256()
    for name in columns:
        h.update(name.encode())
        h.update(np.ascontiguousarray(res.signals[name], dtype=np.float64).tobytes())
    summary = res.summary()
    return {
        "status": int(res.status),
        "k_end": int(res.k_end),
        "columns": list(columns),
        "signals_sha256": h.hexdigest(),
        "final": {k: summary["final"][k] for k in columns},
        "energy_J": summary["energy_J"],
        "compensation": summary["compensation"],
    }


def main() -> None:
    from imdrive.config.presets import preset_names
    from imdrive.config.scenario import Scenario
    from imdrive.run.simulate import simulate

    data = {}
    for name in preset_names():
        res = simulate(Scenario.read(name))
        data[name] = fingerprint(res, res.columns)
        print(name, data[name]["signals_sha256"][:12], flush=True)
    OUT.write_text(json.dumps(data, indent=1) + "\n")


if __name__ == "__main__":
    main()
