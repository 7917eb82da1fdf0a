"""A recording sampled ``q`` times faster than the controller, brought to the controller's
period, in chunks.

Each recording column is brought down its own way (:class:`Decimator`):

* **measured signals** (currents, encoder speed, DC-link voltage): low-pass filtered, then
  every ``q``-th sample kept. The filter is a linear-phase FIR (``scipy.signal.firwin``,
  Kaiser window, ``16 q + 1`` taps, cut-off at 0.8 of the controller's Nyquist frequency)
  applied centred, its delay of ``8 q`` fast samples taken out: no phase lag at any
  frequency, which matters because the estimators compare the current with the voltage
  (a lag of a few samples is a speed error). It attenuates by about 80 dB from the
  controller's Nyquist frequency up, so the PWM ripple of a scope capture does not alias
  into the controller-rate samples (Oppenheim & Schafer, *Discrete-Time Signal Processing*,
  3rd ed., Pearson 2010, sec. 4.6 and 7.5). Fast samples beyond the ends are the end values.
* **voltages** (``v_alpha_cmd_V``, ``v_beta_cmd_V``): the mean of the ``q`` fast samples of
  each control period ``[t_k, t_k + Ts)``. The estimators integrate the voltage over a
  period, so the period's mean is exactly what they need (a commanded voltage held over the
  period comes back as the command itself), and a moving mean over ``Ts`` is itself an
  anti-aliasing filter with zeros at every multiple of ``1/Ts``.
* **the controller's values** (time, angle, references, its model): the sample at ``t_k``,
  as the estimator would have read it.

Row ``k`` of the result is the fast row ``k q``; a last, incomplete control period is
dropped.
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
    """The anti-aliasing FIR for decimation by ``q``: ``16 q + 1`` taps, linear phase,
    cut-off at 0.8 of the decimated Nyquist frequency, Kaiser window (beta 8), unit DC gain."""
    from scipy.signal import firwin

    h = firwin(16 * q + 1, 0.8 / q, window=("kaiser", 8.0))
    return h / h.sum()


class Decimator:
    """Decimate a recording's columns by the integer ``q``, a chunk at a time
    (module docstring). Consecutive :meth:`push` calls and a final :meth:`finish` give the
    rows one call on the whole recording would."""

    def __init__(self, q: int):
        self.q = int(q)
        self.h = antialias_fir(self.q)
        self.D = (len(self.h) - 1) // 2  # the FIR's delay, fast samples
        self._buf: dict | None = None  # fast samples from row self._m0 - D on (filtered)
        self._m0 = 0  # fast index of the next output row's sample, relative to the buffer

    def push(self, chunk: dict) -> dict:
        """The decimated rows that ``chunk`` (the next fast rows) completes."""
        return self._take(chunk, final=False)

    def finish(self) -> dict:
        """The rows left at the end of the recording."""
        return self._take(None, final=True)

    def _take(self, chunk, final: bool) -> dict:
        q, D = self.q, self.D
        if self._buf is None:
            if chunk is None:
                return {}
            # D fast samples before the first: the first value (filtered columns only)
            self._buf = {n: np.concatenate([np.full(D, v[0]), v]) for n, v in chunk.items()}
        elif chunk is not None:
            self._buf = {n: np.concatenate([self._buf[n], v]) for n, v in chunk.items()}
        buf = self._buf
        n = len(next(iter(buf.values())))
        # output j is the fast sample at buffer index c_j = D + j q: its filter window is
        # buffer[j q : j q + 2 D + 1], its period buffer[c_j : c_j + q]
        if final:  # the last value stands for the samples beyond the end
            buf = {k: np.concatenate([v, np.full(D, v[-1])]) for k, v in buf.items()}
            n_out = max(0, (n - D) // q)  # whole periods only
        else:  # whole filter windows only (D >= q - 1: the period is inside)
            n_out = max(0, (n - 1 - 2 * D) // q + 1)
        out = {}
        if n_out:
            idx = D + q * np.arange(n_out)
            for name, v in buf.items():
                if name in FILTERED:
                    win = np.lib.stride_tricks.sliding_window_view(v, len(self.h))
                    out[name] = win[idx - D] @ self.h
                elif name in AVERAGED:
                    out[name] = v[D : D + n_out * q].reshape(n_out, q).mean(axis=1)
                else:
                    out[name] = v[idx]
        keep_from = q * n_out  # the next output's window starts at buffer index q n_out
        self._buf = {k: v[keep_from:] for k, v in self._buf.items()}
        return out
