"""Progress bars (imdrive._progress): when they show, what they show, and in which form."""

from __future__ import annotations

import io

from imdrive._progress import Progress
from imdrive.studies.paper import STEP_FORMAT


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _run(bar: Progress, start: int | None, steps) -> None:
    if start is not None:
        bar.start(start)
    for n in steps:
        bar.advance(n)
    bar.close()


def test_quiet_off_a_terminal_unless_enabled():
    log = io.StringIO()
    _run(Progress(10, "sweep x", stream=log), 0, [5, 5])
    assert log.getvalue() == ""
    tty = Terminal()
    _run(Progress(10, "sweep x", stream=tty, enabled=False), 0, [5, 5])
    assert tty.getvalue() == ""
    p = Progress(10, "x", stream=io.StringIO())
    p.advance(4)
    assert p.done == 4  # counted even when quiet


def test_on_a_terminal_the_bar_is_redrawn_in_place():
    tty = Terminal()
    _run(Progress(8, "sweep y", unit="runs", stream=tty), 0, [2, 2, 4])
    text = tty.getvalue()
    assert text.startswith("\rsweep y [") and text.endswith("\n")
    assert text.count("\n") == 1
    frames = text.rstrip("\n").split("\r")[1:]
    assert [f.split("]")[1].split()[0] for f in frames][:4] == ["0/8", "2/8", "4/8", "8/8"]
    assert "8/8 runs 100%" in frames[-1] and "[" + "#" * 30 + "]" in frames[-1]


def test_a_resumed_count_starts_at_the_done_items():
    tty = Terminal()
    _run(Progress(100, "s", unit="runs", stream=tty), 40, [10])
    frames = tty.getvalue().rstrip("\n").split("\r")[1:]
    assert "40/100 runs  40%" in frames[0] and "50/100 runs  50%" in frames[-1]


def test_line_mode_prints_one_line_per_update_for_logs():
    log = io.StringIO()
    bar = Progress(4, "sweep z", unit="runs", stream=log, enabled=True, lines=None)
    _run(bar, 0, [1, 3])
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue()
    assert len(lines) == 3 and "0/4 runs" in lines[0] and "4/4 runs 100%" in lines[2]
    # lines=None on a terminal: redrawn
    tty = Terminal()
    _run(Progress(4, "z", stream=tty, enabled=True, lines=None), 0, [4])
    assert tty.getvalue().startswith("\r")


def test_notes_and_a_custom_format_as_the_paper_uses_them():
    log = io.StringIO()
    bar = Progress(3, unit="steps", stream=log, enabled=True, lines=None, bar_format=STEP_FORMAT)
    with bar as p:
        for msg in ("first", "second", "third"):
            p.advance(1, note=msg)
    lines = log.getvalue().splitlines()
    assert len(lines) == 3  # no line for 0 steps done
    assert lines[0].startswith("[ 1/3]") and lines[0].endswith(" s  first")
    assert lines[2].startswith("[ 3/3]") and lines[2].endswith("third")
