"""Issue 39: a scenario file without ``[drive]`` runs open loop (the default) and silently
ignored its ``[control]``. Keys of a section only vector control reads, with no ``[drive]
mode``, now get a deprecation warning naming the sections (the file still runs open loop, as
before: deprecate, don't break); a file that says what it wants runs as before."""

from __future__ import annotations

import pytest

from imdrive import Scenario
from imdrive.cli import main
from imdrive.config.checks import vector_only_sections
from imdrive.errors import ConfigError, ConfigWarning


def test_control_without_drive_warns_naming_the_sections():
    text = '[control]\nspeed_feedback = "mras"\n[compensator]\nenabled = true\n'
    with pytest.warns(ConfigWarning) as rec:
        sc = Scenario.from_toml(text)
    assert sc.drive.mode == "open-loop"  # deprecated, not broken
    msg = " ".join(str(w.message) for w in rec if "drive.mode" in str(w.message))
    assert "[control], [compensator]" in msg
    assert 'mode = "vector"' in msg and 'mode = "open-loop"' in msg


@pytest.mark.parametrize(
    ("section", "key", "value"),
    [
        ("estimator", "R1_ratio", 1.1),
        ("mras", "K1", 50.0),
        ("injection", "amplitude_pu", 0.1),
        ("afo", "rho", 0.5),
    ],
)
def test_every_vector_only_section_counts(section, key, value):
    assert section in vector_only_sections()
    with pytest.warns(ConfigWarning, match=rf"^drive.mode: .*\[{section}\]"):
        Scenario.from_dict({section: {key: value}})


def test_a_bad_key_of_the_section_is_named_first():
    with pytest.raises(ConfigError, match="control.speed_kp: must be finite"):
        Scenario.from_dict({"control": {"speed_kp": float("inf")}})


def test_files_that_say_what_they_want_run_as_before():
    assert Scenario.from_toml("[load]\ntorque_Nm = 1.0\n").drive.mode == "open-loop"
    assert Scenario.from_toml("[control]\n").drive.mode == "open-loop"  # an empty table
    ol = Scenario.from_toml('[drive]\nmode = "open-loop"\n[control]\nspeed_feedback = "mras"\n')
    assert ol.drive.mode == "open-loop"
    vec = Scenario.from_toml('[drive]\nmode = "vector"\n[control]\nspeed_feedback = "mras"\n')
    assert vec.drive.mode == "vector"
    assert Scenario.from_dict(vec.to_dict()) == vec  # a summary's full scenario reads back
    free = Scenario.read("free-acceleration", ["control.speed_feedback=mras"])
    assert free.drive.mode == "open-loop"  # the preset's [drive] is explicit


def test_the_command_line_says_it(tmp_path, capsys):
    f = tmp_path / "mine.toml"
    f.write_text('name = "mine"\n[control]\nspeed_feedback = "mras"\n')
    assert main(["show", str(f)]) == 0
    err = capsys.readouterr().err
    assert "drive.mode: not given" in err and "[control]" in err
