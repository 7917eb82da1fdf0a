"""Processes saving to one numba cache index at once: how many entries survive, and how many
name another entry's data (machine code loaded for the wrong signature).

    python benchmarks/cache_race.py            # numba's own save
    python benchmarks/cache_race.py --imdrive  # the package's locked save (imdrive._cache)
    python benchmarks/cache_race.py --procs 4 --entries 100 --repeat 5

Not a speed measure: each process saves ``--entries`` entries of its own, all starting at the
same moment, into a folder under a temporary ``IMDRIVE_CACHE_DIR``.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import tempfile
import time
from pathlib import Path

from _measured import machine_line


def _worker(folder: str, who: int, n: int, start: float, locked: bool) -> None:
    if locked:
        from imdrive import _cache

        _cache.install()
    from numba.core.caching import IndexDataCacheFile

    index = IndexDataCacheFile(folder, "kernel-1.py", "stamp")
    while time.time() < start:
        pass
    for i in range(n):
        index.save((who, i), (who, i))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--imdrive", action="store_true", help="the package's locked save")
    ap.add_argument("--procs", type=int, default=2)
    ap.add_argument("--entries", type=int, default=40)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(machine_line())
    from numba.core.caching import IndexDataCacheFile

    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory() as tmp:
            os.environ["IMDRIVE_CACHE_DIR"] = tmp
            folder = Path(tmp) / "imdrive.kernels.engine-0"
            folder.mkdir()
            start = time.time() + 1.0
            procs = [
                mp.Process(target=_worker, args=(str(folder), w, args.entries, start, args.imdrive))
                for w in range(args.procs)
            ]
            for p in procs:
                p.start()
            for p in procs:
                p.join()
            index = IndexDataCacheFile(str(folder), "kernel-1.py", "stamp")
            kept = index._load_index()
            wrong = sum(index.load(k) != k for k in kept)
            total = args.procs * args.entries
            print(
                f"{'imdrive' if args.imdrive else 'numba'}: {len(kept)} of {total} entries "
                f"kept, {wrong} naming another entry's data"
            )


if __name__ == "__main__":
    main()
