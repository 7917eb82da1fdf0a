"""imdrive.config.user_files: the checks of a path the user gives, and the bounded reader."""

from __future__ import annotations

import errno
import os

import pytest

from imdrive.config.user_files import (
    lexists,
    path_form_problem,
    read_user_file,
    read_user_text,
    user_file_problem,
    user_folder_problem,
    users_path_error,
)
from imdrive.errors import ConfigError


@pytest.mark.parametrize(
    "text, expected",
    [
        ("", "is empty"),
        ("  ", "is empty"),
        ("a\0b", "NUL byte"),
        ("a" * 256, "longer than 255 bytes"),
        ("/".join(["b" * 200] * 25), "longer than 4096 bytes"),
        ("\udcff", None),  # a surrogate-escaped byte: a name Linux holds
        (5, "must be a path"),
        (b"motor.toml", "got bytes"),
    ],
)
def test_path_form(text, expected):
    problem = path_form_problem(text)
    assert (problem is None) if expected is None else (expected in problem)


def test_read_user_file_bounds_and_kinds(tmp_path):
    f = tmp_path / "f.toml"
    f.write_bytes(b"\xef\xbb\xbfa = 1\n")
    assert read_user_text(f, "scenario", 100) == "a = 1\n"
    with pytest.raises(ConfigError, match=r"^scenario: .*bytes, more than a file holds"):
        read_user_file(f, "scenario", 4)
    (tmp_path / "bin").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ConfigError, match="not UTF-8"):
        read_user_text(tmp_path / "bin", "scenario", 100)
    os.mkfifo(tmp_path / "fifo")
    with pytest.raises(ConfigError, match="is a FIFO, not a regular file"):
        read_user_file(tmp_path / "fifo", "scenario", 100)  # would block without O_NONBLOCK
    with pytest.raises(ConfigError, match="no such file or folder"):
        read_user_file(tmp_path / "none", "scenario", 100)
    with pytest.raises(ConfigError, match="a part of the path is a file"):
        read_user_file(f / "x", "scenario", 100)


def test_file_and_folder_problems(tmp_path):
    assert user_file_problem(tmp_path) == f"{tmp_path} is a folder, not a regular file (file)"
    assert user_folder_problem(tmp_path) is None
    f = tmp_path / "f"
    f.write_text("")
    assert user_folder_problem(f) == f"{f} is a file, not a folder"
    assert "character device" in user_file_problem("/dev/null")
    assert not lexists(tmp_path / ("a" * 300)) and not lexists("a\0") and lexists(tmp_path)


def test_users_path_error_matches_only_a_given_path_and_form_errors(tmp_path):
    given = str(tmp_path / "out")
    long = OSError(errno.ENAMETOOLONG, "File name too long", given + "/summary.json")
    assert users_path_error(long, ["run", "x", "--out", given])
    assert users_path_error(long, ["run", "x", f"--out={given}"])
    assert users_path_error(long, ["run", "x"]) is None  # not a path the user gave
    full = OSError(errno.ENOSPC, "No space left on device", given + "/summary.json")
    assert users_path_error(full, ["run", "x", "--out", given]) is None  # the environment
    rel = OSError(errno.ENOTDIR, "Not a directory", str(tmp_path / "m.toml" / "x.toml"))
    assert users_path_error(rel, ["--set", "machine.file=m.toml/x.toml"])
