"""Regenerate ``preset_baseline.json``: every preset's summary metrics and a hash of its signals.

Run from the repository root only when a change of the numerics is *intended* (say so in the
commit message)::

    python tests/data/make_preset_baseline.py

``tests/drive/test_preset_baseline.py`` compares every preset against this file bit for bit: a
change that is not meant to alter the numerics (a refactor, a rename) must not change a single
bit of any result.

The stored file predates the naming glossary, which renamed the columns ``R2_est_ohm`` and
``R1_est_ohm`` to ``R2_hat_ohm`` and ``R1_hat_ohm`` and the compensation metrics
``R2_est_*`` to ``R2_hat_*`` (:data:`imdrive.run.columns.RENAMED_COLUMNS`,
:data:`~imdrive.run.columns.RENAMED_METRICS`). :func:`fingerprint` reads a column asked for by
its old name under the new one and hashes it under the name asked for, so the stored hashes
still compare the same bytes; a regenerated file uses the new names.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from imdrive.run.columns import RENAMED_COLUMNS, RENAMED_METRICS

HERE = Path(__file__).resolve().parent
OUT = HERE / "preset_baseline.json"


def fingerprint(res, columns) -> dict:
    """Status, final values, energies, compensation metrics and a SHA-256 of the columns.

    ``columns`` are the names to hash, in order; a renamed column's old name is read under its
    new name and hashed (and keyed) under the old one. When ``columns`` use the old names, so
    do the compensation metrics' keys.
    """
    h = hashlib.sha256()
    for name in columns:
        h.update(name.encode())
        values = res.signals[RENAMED_COLUMNS.get(name, name)]
        h.update(np.ascontiguousarray(values, dtype=np.float64).tobytes())
    summary = res.summary()
    comp = summary["compensation"]
    if comp is not None and any(name in RENAMED_COLUMNS for name in columns):
        old = {new: old for old, new in RENAMED_METRICS.items()}
        comp = {old.get(k, k): v for k, v in comp.items()}
    return {
        "status": int(res.status),
        "k_end": int(res.k_end),
        "columns": list(columns),
        "signals_sha256": h.hexdigest(),
        "final": {k: summary["final"][RENAMED_COLUMNS.get(k, k)] for k in columns},
        "energy_J": summary["energy_J"],
        "compensation": comp,
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
