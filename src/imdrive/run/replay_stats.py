"""What a replay accumulates chunk by chunk of each estimator (:mod:`imdrive.run.replay`):
its speed-estimate error against the encoder, and R2_hat's range and settled spread."""

from __future__ import annotations

import math

import numpy as np

#: the share of the replay, at its end, over which R2_hat's mean and spread are given
TAIL = 0.2


class ErrorStats:
    """The speed-estimate error against the encoder, accumulated chunk by chunk."""

    def __init__(self):
        self.n, self.s, self.s2, self.mx = 0, 0.0, 0.0, 0.0

    def add(self, e: np.ndarray) -> None:
        if e.size:
            self.n += e.size
            self.s += float(np.sum(e))
            self.s2 += float(np.sum(e * e))
            self.mx = max(self.mx, float(np.max(np.abs(e))))

    def stats(self) -> dict | None:
        if self.n == 0:
            return None
        return {"mean": self.s / self.n, "rms": math.sqrt(self.s2 / self.n), "max": self.mx}


class R2Spread:
    """R2_hat's range over the replay and its mean and spread (standard deviation) over the
    last :data:`TAIL` of it, accumulated chunk by chunk (the rows to come are known)."""

    def __init__(self, n_rows: int):
        self.lo, self.hi = math.inf, -math.inf
        self.tail_from = int(n_rows * (1.0 - TAIL))  # the first row of the tail
        self.k = 0
        self.ref = None  # the tail's first value: its sums are of the differences from it
        self.n, self.s, self.s2 = 0, 0.0, 0.0

    def add(self, R2: np.ndarray) -> None:
        self.lo = min(self.lo, float(np.min(R2)))
        self.hi = max(self.hi, float(np.max(R2)))
        tail = R2[max(self.tail_from - self.k, 0) :]
        if tail.size:
            if self.ref is None:
                self.ref = float(tail[0])
            d = tail - self.ref
            self.n += tail.size
            self.s += float(np.sum(d))
            self.s2 += float(np.sum(d * d))
        self.k += R2.size

    def stats(self) -> dict | None:
        if self.n == 0:
            return None
        mean = self.s / self.n
        return {
            "min": self.lo,
            "max": self.hi,
            "tail_mean": self.ref + mean,
            "tail_std": math.sqrt(max(self.s2 / self.n - mean * mean, 0.0)),
            "tail_share": TAIL,
        }
