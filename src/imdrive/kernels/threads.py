"""Kernels over the cores: Python threads, each running a compiled worker that releases the GIL.

numba's ``prange`` makes the parallel loop an entry point of its own (a gufunc), which links
and optimises again everything its body calls and, with an unsigned index, compiles the body's
callees a second time: the batch's and the stability map's first use compiled seconds more
than a worker called from a thread (benchmarks/README.md, 2026-11-30). The same worker serves
one thread, several, and a dask worker.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numba


def num_threads() -> int:
    """Threads the kernels run on: numba's (``NUMBA_NUM_THREADS``, ``numba.set_num_threads``)."""
    return numba.get_num_threads()


def slots(n_items: int) -> int:
    """Threads to deal ``n_items`` to: one per item, at most :func:`num_threads`, at least 1."""
    return max(min(int(n_items), num_threads()), 1)


def over_threads(call, n_slots: int) -> None:
    """``call(slot)`` for ``slot`` in ``range(n_slots)``, each on a thread of its own (on the
    calling thread when there is one); an exception of any of them is raised here.

    ``call`` should run a kernel compiled with ``nogil=True``, or the threads take turns.
    """
    if n_slots <= 1:
        call(0)
        return
    with ThreadPoolExecutor(n_slots) as pool:
        jobs = [pool.submit(call, slot) for slot in range(n_slots)]
        for job in jobs:
            job.result()
