"""A word on the console whenever numba compiles for more than 2 s.

Every command that runs a kernel may meet a cold cache: ``run`` (the drive), ``sweep`` (the
batch kernels), ``stability`` (the linearisation), ``bench-estimators`` (one drive per
estimator). Rather than each command guessing whether it will compile, one numba event
listener (``numba:compile``) watches the outermost compilation: once it has lasted
:data:`SHOW_AFTER_S`, it prints ``imdrive: compiling kernels for first use (run_drive, about
N s) ...`` on stderr and, on a terminal, a bar over the expected time; when it ends, the time it
took, which is kept (``compile-times.json`` in the cache root) as the next estimate.

The command line enables it (:func:`enable`, not under ``-q``); :mod:`imdrive.kernels` attaches
the listener when it is imported (:func:`attach`), so a command that never loads numba never
pays for it. A library user gets nothing printed unless they call :func:`enable` themselves.
This module imports nothing of imdrive at import time.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import sys
import threading
import time

#: A compilation shorter than this says nothing.
SHOW_AFTER_S = 2.0
_FILE = "compile-times.json"

_wanted = False
_attached = False
_stream = None  # where the notices go (None: sys.stderr at the time)


def enable(stream=None) -> None:
    """Announce compilations longer than :data:`SHOW_AFTER_S` on ``stream`` (stderr)."""
    global _wanted, _stream
    _wanted = True
    _stream = stream
    if "imdrive.kernels" in sys.modules:  # kernels already loaded: attach now
        attach()


def _times_path():
    from imdrive._cache import cache_root

    return cache_root() / _FILE


def _estimate(name: str) -> float | None:
    with contextlib.suppress(OSError, ValueError, TypeError):
        value = json.loads(_times_path().read_text()).get(name)
        if isinstance(value, int | float) and value > 0:
            return float(value)
    return None


def _remember(name: str, seconds: float) -> None:
    with contextlib.suppress(OSError, ValueError, TypeError):
        path = _times_path()
        try:
            times = json.loads(path.read_text())
            times = times if isinstance(times, dict) else {}
        except (OSError, ValueError):
            times = {}
        times[name] = round(seconds, 1)
        tmp = path.with_name(f"{_FILE}.{id(times)}.tmp")
        tmp.write_text(json.dumps(times, indent=0, sort_keys=True))
        tmp.replace(path)


class _Notice:
    """The line (and bar) of one outermost compilation, drawn by a timer thread."""

    def __init__(self, name: str, stream, key: str | None = None):
        self.name = name
        self.key = key or name  # what the time is kept under: one specialisation's own
        self.stream = stream
        self.t0 = time.perf_counter()
        self.estimate = _estimate(self.key)
        self.shown = False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()

    def _watch(self) -> None:
        if self._stop.wait(SHOW_AFTER_S):
            return
        about = f"about {self.estimate:.0f} s" if self.estimate else "up to a minute"
        print(
            f"imdrive: compiling kernels for first use ({self.name}, {about}; cached after) ...",
            file=self.stream,
            flush=True,
        )
        self.shown = True
        tty = getattr(self.stream, "isatty", lambda: False)()
        if not (tty and self.estimate):
            return
        from imdrive._progress import Progress

        total = max(1, round(self.estimate))
        bar = Progress(total, "  compiling", unit="s", enabled=True, stream=self.stream)
        bar.start(done=0)
        shown = 0
        while not self._stop.wait(0.5):
            now = min(total, int(time.perf_counter() - self.t0))
            if now > shown:
                bar.advance(now - shown)
                shown = now
        bar.close()

    def end(self) -> None:
        self._stop.set()
        self._thread.join()
        took = time.perf_counter() - self.t0
        if took >= SHOW_AFTER_S:
            _remember(self.key, took)
        if self.shown:
            print(f"imdrive: compiled {self.name} in {took:.1f} s", file=self.stream, flush=True)


def _key(name: str, data) -> str:
    """What a compilation's time is kept under: the function and its argument types. One
    function compiles for several records (the batch's ``_worker`` once per estimator, 8-22 s
    each, measured 2026-12-01): keyed by the name alone, the first one's time was every other
    one's estimate."""
    args = str(data.get("args", "")) if isinstance(data, dict) else ""
    return f"{name}:{hashlib.sha1(args.encode()).hexdigest()[:10]}" if args else name


def attach():
    """Register the listener with numba if :func:`enable` was called (once per process).

    Returns
    -------
    numba.core.event.Listener or None
        The listener registered now, or None.
    """
    global _attached
    if not _wanted or _attached:
        return None
    from numba.core import event

    class _Listener(event.Listener):
        def __init__(self):
            self.depth = 0
            self.notice: _Notice | None = None

        def on_start(self, ev):
            self.depth += 1
            if self.depth == 1:
                disp = ev.data.get("dispatcher")
                func = getattr(disp, "py_func", None)
                name = getattr(func, "__name__", "kernel")
                self.notice = _Notice(name, _stream or sys.stderr, _key(name, ev.data))

        def on_end(self, ev):
            self.depth -= 1
            if self.depth == 0 and self.notice is not None:
                self.notice.end()
                self.notice = None

    listener = _Listener()
    event.register("numba:compile", listener)
    _attached = True
    return listener
