"""A compilation longer than 2 s says so on the console (imdrive._compiling)."""

from __future__ import annotations

import io
import json
import time

from numba import njit
from numba.core import event

from imdrive import _compiling


def test_a_long_compilation_is_announced_and_timed(monkeypatch, tmp_path):
    monkeypatch.setenv("IMDRIVE_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(_compiling, "SHOW_AFTER_S", 0.05)
    out = io.StringIO()
    notice = _compiling._Notice("run_drive", out)
    time.sleep(0.3)
    notice.end()
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("imdrive: compiling kernels for first use (run_drive, up to a")
    assert lines[-1].startswith("imdrive: compiled run_drive in 0.")
    # the time taken is the next estimate
    assert json.loads((tmp_path / "compile-times.json").read_text())["run_drive"] > 0.2
    out = io.StringIO()
    notice = _compiling._Notice("run_drive", out)
    time.sleep(0.2)
    notice.end()
    assert "(run_drive, about 0 s;" in out.getvalue()


def test_a_short_compilation_says_nothing(monkeypatch, tmp_path):
    monkeypatch.setenv("IMDRIVE_CACHE_DIR", str(tmp_path))
    out = io.StringIO()
    notice = _compiling._Notice("quick", out)  # SHOW_AFTER_S = 2 s
    notice.end()
    assert out.getvalue() == ""
    assert not (tmp_path / "compile-times.json").exists()


def test_the_listener_watches_the_outermost_compilation(monkeypatch):
    seen, keys = [], []

    class Recorder:
        def __init__(self, name, stream, key=None):
            seen.append(name)
            keys.append(key)

        def end(self):
            seen.append("end")

    monkeypatch.setattr(_compiling, "_Notice", Recorder)
    monkeypatch.setattr(_compiling, "_attached", False)
    monkeypatch.setattr(_compiling, "_wanted", True)
    listener = _compiling.attach()
    assert listener is not None

    @njit
    def inner(x):
        return x + 1.0

    @njit
    def outer(x):
        return inner(x) * 2.0

    try:
        assert outer(1.0) == 4.0
    finally:
        event.unregister("numba:compile", listener)
    # one notice, for the outermost function only (a listener that an earlier command line of
    # this process attached makes its own, the same)
    assert seen and sorted(seen) == ["end"] * (len(seen) // 2) + ["outer"] * (len(seen) // 2)
    # its time is kept under the function and its argument types
    assert keys[0].startswith("outer:") and keys[0] != "outer:"


def test_each_specialisation_keeps_its_own_time(monkeypatch, tmp_path):
    """One function compiled for two argument types (the batch's worker for two estimators):
    the second is not announced with the first one's time."""
    monkeypatch.setenv("IMDRIVE_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(_compiling, "SHOW_AFTER_S", 0.05)
    notice = _compiling._Notice("_worker", io.StringIO(), key="_worker:aaaa")
    time.sleep(0.3)
    notice.end()
    out = io.StringIO()
    notice = _compiling._Notice("_worker", out, key="_worker:bbbb")
    time.sleep(0.2)
    notice.end()
    assert "(_worker, up to a minute;" in out.getvalue()
    out = io.StringIO()
    notice = _compiling._Notice("_worker", out, key="_worker:aaaa")
    time.sleep(0.2)
    notice.end()
    assert "(_worker, about 0 s;" in out.getvalue()


def test_the_command_line_enables_it_unless_quiet(monkeypatch):
    from imdrive.cli import main

    calls = []
    monkeypatch.setattr(_compiling, "enable", lambda *a, **k: calls.append(1))
    assert main(["show", "sensorless"]) == 0
    assert calls == [1]
    calls.clear()
    assert main(["run", "nosuchpreset", "-q"]) == 2
    assert calls == []
