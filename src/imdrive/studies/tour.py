"""The library tour: every library machine with three presets and only ``machine.preset``
changed (docs/machines.md, ``python -m imdrive.studies.doctables --run library-tour``).

The presets state what depends on the machine in per-unit of it (speed and load profiles,
gains, the injection, the R2 clamps; config/perunit.py), the drive sequences its start from
the machine's rotor (premagnetisation, config/sequence.py), the realistic drive takes the
tables an ideal commissioning identifies on its own plant (``controller_model.ideal``), and
the R2-tracking preset runs for a number of its decision windows
(``simulation.tracking_windows``), which follow the rotor's corner. So a user's machine needs
no other edit: the tour runs each preset on each machine with no warning, and tells whether
each reaches its steady state ("ok") and, for ``injection-robust``, where R̂2 ends.
"""

from __future__ import annotations

import warnings

import pandas as pd

from imdrive.config.machine import machine_presets
from imdrive.config.scenario import Scenario

#: The presets of the tour: the sensorless drive, the recommended R2-tracking drive and the
#: realistic (switching bridge, sensors, saturation, commissioned) sensorless drive.
PRESETS = ("sensorless", "injection-robust", "sensorless-realistic")


def run(machines=None, presets=PRESETS) -> pd.DataFrame:
    """Run every preset of ``presets`` on every machine of ``machines`` (default: the
    library), only ``machine.preset`` changed.

    Returns
    -------
    DataFrame
        ``machine``, ``preset``, ``warnings`` (the ConfigWarnings reading the scenario gave,
        joined; empty: none) and the batch metrics with their verdicts
        (:func:`imdrive.run.batch.simulate_batch`), one row per run.
    """
    from imdrive.run.batch import simulate_batch

    rows, scs = [], []
    for m in machines or machine_presets():
        for p in presets:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                scs.append(Scenario.read(p, [f'machine.preset="{m}"']))
            said = [str(w.message) for w in caught if "Warning" in w.category.__name__]
            rows.append({"machine": m, "preset": p, "warnings": " | ".join(said)})
    res = simulate_batch(scs, errors="record")
    metrics = res.metrics.drop(columns=["drive"], errors="ignore").reset_index(drop=True)
    return pd.concat([pd.DataFrame(rows), metrics], axis=1)


def _cell(r) -> str:
    """One run's cell: its verdict, the R̂2 error where R2 is tracked, the run's length."""
    verdict = "**" + str(r["verdict"]) + "**" if r["verdict"] != "ok" else "ok"
    out = verdict
    if r["preset"] == "injection-robust":
        out += f", R̂2 {float(r['R2_error_pct']):+.3f} %"
    out += f" ({float(r['simulated_s']):.3g} s)"
    if isinstance(r["warnings"], str) and r["warnings"]:
        out += ", warned"
    return out


def lines(df: pd.DataFrame) -> list[str]:
    """The tour's table: a row per machine, a column per preset."""
    presets = list(dict.fromkeys(df["preset"]))
    out = [
        "| machine | " + " | ".join(f"`{p}`" for p in presets) + " |",
        "|---|" + "---|" * len(presets),
    ]
    for m, g in df.groupby("machine", sort=False):
        g = g.set_index("preset")
        out.append(
            f"| `{m}` | "
            + " | ".join(_cell(g.loc[p].to_dict() | {"preset": p}) for p in presets)
            + " |"
        )
    ok = int((df["verdict"] == "ok").sum())
    warned = int((df["warnings"].fillna("") != "").sum())
    out += ["", f"{ok} of {len(df)} runs ok; {warned} warned while the scenario was read."]
    return out
