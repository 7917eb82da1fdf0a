"""Shared by every test folder (tests/<layer>/): the tests' own helpers in ``tests/data``
(``from data.make_preset_baseline import fingerprint``) import from any folder."""

import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parent
if str(TESTS) not in sys.path:
    sys.path.insert(0, str(TESTS))


def pytest_configure(config):
    """Before parallel workers start (``-n``), compile every kernel entry point once, on every
    core (``imdrive warm-up``): otherwise each worker compiles the drive for itself, side by
    side. Nothing to do, in about 1 s, when the cache already holds them."""
    if getattr(config, "workerinput", None) is not None:  # a worker: the controller did it
        return
    if not getattr(config.option, "numprocesses", None) or config.option.collectonly:
        return
    import time

    from imdrive.cli.warmup import warm_up

    t0 = time.perf_counter()
    print("conftest: imdrive warm-up (compiles the kernels once for every worker) ...")
    try:
        warm_up(log=print)
    except RuntimeError as exc:  # the tests that need the kernel will show the error
        print(f"conftest: warm-up failed: {exc}")
    print(f"conftest: kernels ready in {time.perf_counter() - t0:.1f} s")
