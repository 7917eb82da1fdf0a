"""A recording sampled ``q`` times faster than the controller, brought to the controller's
period, in chunks.

Each recording column is brought down its own way (:class:`Decimator`):

* **measured signals** (currents, encoder speed, DC-link voltage): low-pass filtered, then
  every ``q``-th sample kept. The filter is a linear-phase FIR (``scipy.signal.firwin``,
  Kaiser window, beta 10, ``24 q + 1`` taps, cut-off at the controller's Nyquist frequency
  ``1/(2 Ts)``, as ``scipy.signal.decimate``'s FIR) applied centred, its delay of ``12 q``
  fast samples taken out: no phase lag at any frequency, which matters because the
  estimators compare the current with the voltage (a lag of a few samples is a speed error).
  Its transition band straddles the Nyquist frequency and it attenuates by about 100 dB
  beyond it, so the PWM ripple near ``1/Ts`` and its multiples (what would alias to low
  frequencies, where the estimators work) is removed, while the current's content below
  ``1/(2 Ts)``, which a controller sampling at ``Ts`` sees, is kept (Oppenheim & Schafer,
  *Discrete-Time Signal Processing*, 3rd ed., Pearson 2010, sec. 4.6 and 7.5). A lower
  cut-off costs accuracy: at 0.6 of the Nyquist frequency the EKF's estimate in
  ``tests/run/test_replay_foreign.py`` moves by 0.14 rpm instead of 0.08. The first and
  last 12 control periods, whose filter window would reach beyond the recording, are
  dropped.
* **voltages** (``v_alpha_cmd_V``, ``v_beta_cmd_V``): the mean of the ``q`` fast samples of
  each control period ``[t_k, t_k + Ts)``. The estimators integrate the voltage over a
  period, so the period's mean is exactly what they need (a commanded voltage held over the
  period comes back as the command itself), and a moving mean over ``Ts`` is itself an
  anti-aliasing filter with zeros at every multiple of ``1/Ts``.
* **the controller's values** (time, angle, references, its model): the sample at ``t_k``,
  as the estimator would have read it.

Row ``k`` of the result is the fast row ``k q``.
"""

from __future__ import annotations

import numpy as np

#: columns filtered and sampled; columns averaged over the period; every other one sampled
FILTERED = (
    "i_alpha_meas_A",
    "i_beta_meas_A",
    "i_a_meas_A",
    "i_b_meas_A",
    "i_c_meas_A",
    "speed_enc_rpm",
    "vdc_meas_V",
)
AVERAGED = ("v_alpha_cmd_V", "v_beta_cmd_V")


def antialias_fir(q: int) -> np.ndarray:
    """The anti-aliasing FIR for decimation by ``q``: ``24 q + 1`` taps, linear phase,
    cut-off at the decimated Nyquist frequency, Kaiser window (beta 10), unit DC gain."""
    from scipy.signal import firwin

    h = firwin(24 * q + 1, 1.0 / q, window=("kaiser", 10.0))
    return h / h.sum()


class Decimator:
    """Decimate a recording's columns by the integer ``q``, a chunk at a time
    (module docstring). Consecutive :meth:`push` calls give the rows one call on the whole
    recording would. Output row ``j`` is the fast row ``j q``, for every ``j`` whose filter
    window lies inside the recording (the first and last :attr:`edge` output rows are not
    given: their window would reach beyond the recording)."""

    def __init__(self, q: int):
        self.q = int(q)
        self.h = antialias_fir(self.q)
        self.D = (len(self.h) - 1) // 2  # the FIR's delay, fast samples
        self.edge = -(-self.D // self.q)  # output rows lost at each end
        self._buf: dict | None = None  # fast samples from the fast row self._b0 on
        self._b0 = 0
        self._c = self.edge * self.q  # the fast row of the next output

    def push(self, chunk: dict) -> dict:
        """The decimated rows that ``chunk`` (the next fast rows) completes."""
        if self._buf is None:
            self._buf = {n: np.asarray(v) for n, v in chunk.items()}
        else:
            self._buf = {n: np.concatenate([self._buf[n], v]) for n, v in chunk.items()}
        q, D = self.q, self.D
        n = len(next(iter(self._buf.values())))
        last = self._b0 + n - 1  # the last fast row present
        n_out = max(0, (last - D - self._c) // q + 1)  # whole windows: c + D <= last
        out = {}
        if n_out:
            c = self._c - self._b0 + q * np.arange(n_out)  # buffer indices of the outputs
            for name, v in self._buf.items():
                if name in FILTERED:
                    win = np.lib.stride_tricks.sliding_window_view(v, len(self.h))
                    out[name] = win[c - D] @ self.h
                elif name in AVERAGED:
                    out[name] = v[c[0] : c[0] + n_out * q].reshape(n_out, q).mean(axis=1)
                else:
                    out[name] = v[c]
            self._c += q * n_out
        drop = self._c - D - self._b0  # samples no window needs any more
        if drop > 0:
            self._buf = {k: v[drop:] for k, v in self._buf.items()}
            self._b0 += drop
        return out
