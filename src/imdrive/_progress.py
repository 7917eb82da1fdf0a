"""Progress bars: one implementation (on tqdm) for sweeps and the paper reproduction.

Classes
-------
Progress
    A bar over a known number of items (runs, steps) on a stream, stderr by default: drawn in
    place on a terminal, quiet elsewhere unless asked for, and optionally one line per update
    for logs.

Notes
-----
tqdm does the formatting (elapsed time, rate, ETA, the bar itself); this module only fixes
the look and the rules: quiet when the stream is not a terminal unless ``enabled=True``, every
update shown (calls are at most a few per second: a chunk of runs, a step of a study), and no
tqdm monitor thread. This module imports nothing of imdrive.
"""

from __future__ import annotations

import sys
import time

from tqdm import tqdm

#: The default look: ``sweep x [#############                 ] 240/567 runs  42% 00:15 elapsed,
#: ETA 00:21`` (one line)
BAR = (
    "{desc} [{bar:30}] {n_fmt}/{total_fmt} {unit} {percentage:3.0f}% "
    "{elapsed} elapsed, ETA {remaining}"
)


class _Tqdm(tqdm):
    monitor_interval = 0  # no background thread: every update is drawn anyway


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


class Progress:
    """A progress bar over ``total`` items.

    Parameters
    ----------
    total : int
        Number of items (runs, steps).
    label : str
        Text before the bar (tqdm's ``desc``); :meth:`advance` may replace it with a note.
    unit : str
        What is counted, shown after the count.
    enabled : bool or None
        None (default): only when ``stream`` is a terminal; True: always; False: never.
    stream : file-like
        Where to draw; ``sys.stderr`` by default.
    lines : bool or None
        False (default): redraw one line in place (``\\r``). True: print one line per update,
        for logs. None: lines when ``stream`` is not a terminal.
    bar_format : str
        A tqdm ``bar_format`` (fields ``desc``, ``bar``, ``n``, ``n_fmt``, ``total``,
        ``total_fmt``, ``unit``, ``percentage``, ``elapsed``, ``elapsed_s``, ``remaining``,
        ...); :data:`BAR` by default.

    Examples
    --------
    >>> bar = Progress(567, "sweep detuning-map", unit="runs")  # doctest: +SKIP
    >>> bar.start(done=48)  # resumed: 48 runs were done before
    >>> bar.advance(24)
    >>> bar.close()
    """

    def __init__(
        self,
        total: int,
        label: str = "",
        *,
        unit: str = "items",
        enabled: bool | None = None,
        stream=None,
        lines: bool | None = False,
        bar_format: str = BAR,
    ):
        self.stream = stream if stream is not None else sys.stderr
        tty = _isatty(self.stream)
        self.enabled = tty if enabled is None else bool(enabled)
        self.lines = (not tty) if lines is None else bool(lines)
        self.total = total
        self.label = label
        self.unit = unit
        self.bar_format = bar_format
        self.done = 0
        self._start_done = 0
        self._t0 = time.perf_counter()
        self._bar: tqdm | None = None
        self._started = False

    # -- counting --------------------------------------------------------------------------
    def start(self, done: int = 0) -> None:
        """Start the clock with ``done`` items already complete (e.g. a resumed sweep).

        Draws the bar at once; without a call, the first :meth:`advance` starts it from 0
        (in line mode without a line for 0 items).

        Parameters
        ----------
        done : int
            Items already complete.
        """
        self._start(done, draw=True)

    def _start(self, done: int, draw: bool) -> None:
        self.done = self._start_done = done
        self._t0 = time.perf_counter()
        self._started = True
        if not self.enabled:
            return
        if self.lines:
            if draw:
                self._write_line()
        else:
            self._bar = _Tqdm(
                total=self.total,
                initial=done,
                desc=self.label,
                unit=self.unit,
                file=self.stream,
                bar_format=self.bar_format,
                ascii=" #",
                mininterval=0,
                miniters=0,
                dynamic_ncols=True,
            )

    def advance(self, n: int = 1, note: str | None = None) -> None:
        """Count more items done.

        Parameters
        ----------
        n : int
            Items just completed.
        note : str, optional
            Replaces the label from now on.
        """
        if not self._started:
            self._start(0, draw=False)
        self.done += n
        if note is not None:
            self.label = note
        if not self.enabled:
            return
        if self.lines:
            self._write_line()
        else:
            if note is not None:
                self._bar.set_description_str(note, refresh=False)
            self._bar.update(n)

    def close(self) -> None:
        """End the bar (a redrawn bar ends with a newline)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- drawing ---------------------------------------------------------------------------
    def _write_line(self) -> None:
        text = tqdm.format_meter(
            self.done,
            self.total,
            time.perf_counter() - self._t0,
            prefix=self.label,
            ascii=" #",
            unit=self.unit,
            bar_format=self.bar_format,
            initial=self._start_done,
        )
        self.stream.write(text + "\n")
        self.stream.flush()
