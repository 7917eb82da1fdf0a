"""What an ideal commissioning run identifies, printed as a ``[controller_model]`` section.

The tables themselves are computed in :mod:`imdrive.config.commissioning_ideal` (a scenario's
``controller_model.ideal = true`` resolves them when it is read); this module keeps their
import path and prints them. Regenerate a section with
``python -m imdrive.analysis.commissioning PRESET``.
"""

from __future__ import annotations

import sys

from imdrive.config.commissioning_ideal import (  # noqa: F401  (their import path)
    FLUX_PU,
    ideal_commissioning,
    plant_inverter_error,
    plant_magnetising_curve,
    plant_secant_inductance,
)
from imdrive.config.scenario import Scenario


def section_toml(tables: dict[str, list[float]]) -> str:
    """The tables as a ``[controller_model]`` TOML section."""
    lines = ["[controller_model]"]
    for key, values in tables.items():
        lines.append(f"{key} = [{', '.join(f'{v:.6g}' for v in values)}]")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """``python -m imdrive.analysis.commissioning PRESET_OR_FILE``: print the section."""
    import argparse

    ap = argparse.ArgumentParser(
        prog="python -m imdrive.analysis.commissioning",
        description="Print the [controller_model] an ideal commissioning gives.",
    )
    ap.add_argument("scenario", metavar="PRESET_OR_FILE")
    args = ap.parse_args(sys.argv[1:] if argv is None else argv)
    print(section_toml(ideal_commissioning(Scenario.read(args.scenario))), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
