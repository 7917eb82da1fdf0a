"""Packing of time profiles into the kernels' arrays."""

from __future__ import annotations

import numpy as np

from imdrive.config.profiles import Profile


def profiles_to_arrays(profiles: list[Profile]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pack profiles into ``(prof_t, prof_v, prof_n)`` arrays for the kernels."""
    K = max(len(p.points) for p in profiles)
    prof_t = np.zeros((len(profiles), K))
    prof_v = np.zeros((len(profiles), K))
    prof_n = np.zeros(len(profiles), dtype=np.int64)
    for k, p in enumerate(profiles):
        t, v = p.arrays()
        n = len(t)
        prof_t[k, :n] = t
        prof_v[k, :n] = v
        prof_n[k] = n
    return prof_t, prof_v, prof_n
