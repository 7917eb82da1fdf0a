"""Property-based tests over every command's flags (issue 40, "must show"): hypothesis draws,
for each command read from the parser, any subset of its flags with hostile values (numbers
in text, NaN, 1e308, separators, control characters, 300-character names, hostile paths) and
hostile positional arguments. A command that writes gets a hostile ``--out`` besides, which
must be refused before any work: exit 2 with one line. Every other outcome must be one of the
documented exits, never 4 or 5, never a traceback, never a hang.

Bounded for CI: a few examples per command, no deadline (a refusal costs milliseconds; an
accepted ``show`` or ``fuzzy-table`` a fraction of a second). ``warm-up`` is left out: an
accepted value compiles every kernel.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from data.hostile import (
    TEXTS,
    WRITERS,
    bounded_property,
    commands,
    flags,
    make_path,
    positionals,
    run_cli,
)

hypothesis = pytest.importorskip("hypothesis")
st = pytest.importorskip("hypothesis.strategies")

#: kinds of --out every writer must refuse (an empty or absent folder is a valid one)
REFUSED_OUT = ("empty", ".", "..", "file", "under-a-file", "fifo", "socket", "device",
               "dangling", "too-long", "foreign-folder", "loop")  # fmt: skip
PATH_KINDS = (*REFUSED_OUT, "folder")
COMMANDS = sorted(n for n in commands() if n != "warm-up")
EXAMPLES = 12


def _value(draw, tmp: Path, name: str) -> str:
    if draw(st.booleans()):
        return make_path(tmp, draw(st.sampled_from(PATH_KINDS)), draw(st.sampled_from(
            ("", ".toml", ".json", ".csv", ".parquet", ".py"))))  # fmt: skip
    return draw(st.sampled_from(TEXTS))


@st.composite
def _argv(draw, command: str, tmp: Path) -> list[str]:
    parser = commands()[command]
    argv = [command]
    for action in positionals(parser):
        n = 2 if action.nargs == "+" else 1
        if action.nargs == "?" and draw(st.booleans()):
            continue
        argv += [_value(draw, tmp, action.dest) for _ in range(n)]
    for flag, takes_value in flags(parser):
        if flag in ("--out", "--force", "--resume", "--list", "--show") and command in WRITERS:
            continue  # the hostile --out below decides; --force would accept a foreign folder
        if not draw(st.booleans()):
            continue
        if not takes_value:
            argv.append(flag)
        else:
            argv += [flag, _value(draw, tmp, flag)]
    if command in WRITERS:
        argv += ["--out", make_path(tmp, draw(st.sampled_from(REFUSED_OUT)))]
    return argv


@pytest.mark.parametrize("command", COMMANDS)
def test_hostile_flags_give_a_documented_outcome(tmp_path_factory, monkeypatch, command):
    monkeypatch.chdir(tmp_path_factory.mktemp("cwd"))  # nothing accepted lands in the checkout

    @bounded_property(EXAMPLES)
    @hypothesis.given(data=st.data())
    def check(data):
        tmp = tmp_path_factory.mktemp(command)
        argv = data.draw(_argv(command, tmp))
        outcome, detail = run_cli(argv, bound_s=60.0)
        assert outcome != "failure", (argv, detail)
        if command in WRITERS:
            assert outcome == "refused", (argv, detail)

    check()
