"""How far one ``simulate()`` call walks through the package's files.

Run from the repository root with the imdrive venv (any tree: it imports the ``imdrive`` on
``sys.path``; ``PYTHONPATH=OTHER_TREE/src`` measures another)::

    python benchmarks/walk_simulate.py [PRESET]

The scenario is read and the kernels are loaded first (not counted); then, on the scenario
read again (so nothing the first run resolved and memoised is reused), one ``simulate()``
of the preset (default ``sensorless``, cut to one control period, since the compiled loop is
not Python and is not traced) runs under :func:`sys.setprofile`. The walk is the sequence of
the files of every Python function called inside ``imdrive``, in call order. A *file switch*
is a call into another file than the previous call's. A *climb* is a switch into a file of a
higher layer than the previous call's (ranks as in ``tests/package/test_layers.py``: config 1,
kernels 2, design 3, fuzzy/analysis 4, run 5, sweep/studies/stability/bench 6, cli 7): the
walk went down and has to come back up. Prints the counts and the files visited.
"""

from __future__ import annotations

import sys
from pathlib import Path

RANK = {
    "config": 1,
    "kernels": 2,
    "design": 3,
    "fuzzy": 4,
    "analysis": 4,
    "run": 5,
    "sweep": 6,
    "studies": 6,
    "stability": 6,
    "bench": 6,
    "commission": 6,
    "cli": 7,
}


def _module(filename: str, root: Path) -> str | None:
    p = Path(filename)
    try:
        rel = p.resolve().relative_to(root)
    except ValueError:
        return None
    return str(rel)


def _rank(rel: str) -> int:
    return RANK.get(rel.split("/")[0], 0)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    preset = argv[0] if argv else "sensorless"
    import imdrive
    from imdrive import Scenario
    from imdrive.run.simulate import simulate

    root = Path(imdrive.__file__).resolve().parent
    sc = Scenario.read(preset, [f"simulation.t_end_s={Scenario.read(preset).simulation.Ts_s}"])
    simulate(sc)  # load the kernels and every module first
    # a fresh scenario object (read, not counted): nothing resolved on the first run is reused
    sc = Scenario.read(preset, [f"simulation.t_end_s={Scenario.read(preset).simulation.Ts_s}"])
    calls: list[str] = []  # the file of every call, in order

    def prof(frame, event, arg):
        if event == "call":
            rel = _module(frame.f_code.co_filename, root)
            if rel is not None:
                calls.append(rel)

    sys.setprofile(prof)
    try:
        simulate(sc)
    finally:
        sys.setprofile(None)
    pairs = list(zip(calls, calls[1:], strict=False))
    switches = sum(1 for a, b in pairs if a != b)
    climbs = sum(1 for a, b in pairs if a != b and _rank(b) > _rank(a))
    files = sorted(set(calls))
    print(
        f"simulate({preset!r}): {switches} file switches through {len(files)} files, "
        f"{climbs} climbs to a higher layer, {len(calls)} calls"
    )
    for f in files:
        print("  ", f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
