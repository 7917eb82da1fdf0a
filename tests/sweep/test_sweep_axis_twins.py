"""Sweep axes that state one quantity twice (absolute and per-unit twins of
:data:`imdrive.config.pairs.PAIRS`), and axes whose values are tables or lists: refused with
one line naming the axes (issue 40, class 8)."""

from __future__ import annotations

import pytest
from data.inprocess import imdrive_here

from imdrive.errors import ConfigError
from imdrive.sweep import parse_sweep

HEAD = 'name = "t"\nbase = "sensorless"\n[set]\nsimulation.t_end_s = 0.02\n[axes]\n'

TWINS = {
    "R2_ohm and R2_ratio keys": (
        '"estimator.R2_ohm" = [0.7, 0.8]\n"estimator.R2_ratio" = [1.0, 1.1]\n',
        ("estimator.R2_ohm", "estimator.R2_ratio"),
    ),
    "R2_ohm key and R2_ratio axis": (
        '"estimator.R2_ohm" = [0.7, 0.8]\nR2_ratio = [1.0, 1.1]\n',
        ("estimator.R2_ohm", "R2_ratio"),
    ),
    "Hz and pu twins": (
        '"injection.frequency_Hz" = [5.0, 6.0]\n"injection.frequency_pu" = [1.0, 1.1]\n',
        ("injection.frequency_Hz", "injection.frequency_pu"),
    ),
    "a variant's R2_ohm under R2_ratio": (
        'R2_ratio = [1.0, 1.1]\n[axes.variant]\na = {}\nb = { "estimator.R2_ohm" = 0.9 }\n',
        ("R2_ratio", "variant", "estimator.R2_ohm"),
    ),
    "mras rate twins in two variants": (
        "[axes.v1]\na = { mras.R1_rate_per_s = 0.5 }\nb = {}\n"
        "[axes.v2]\nc = { mras.R1_rate_pu = 0.1 }\nd = {}\n",
        ("v1", "v2"),
    ),
}


@pytest.mark.parametrize("axes, names", TWINS.values(), ids=TWINS.keys())
def test_twin_axes_are_refused_naming_both(axes, names):
    with pytest.raises(ConfigError, match="twins of one quantity") as exc:
        parse_sweep(HEAD + axes)
    line = str(exc.value)
    assert "\n" not in line
    for n in names:
        assert n in line


TABLES = {
    "measured table": '"controller_model.magnetising_psi_Wb" = '
    "[[[0.0, 1.0], [0.5, 1.0]], [[0.0, 1.0], [0.6, 1.0]]]\n",
    "module lists": '"plugins.modules" = [["a.py"], ["b.py"]]\n',
    "profiles": '"control.speed_ref_rpm" = [{ initial = 0, changes = [{ at = 0.01, to = 600 }] },'
    " { initial = 0, changes = [{ at = 0.01, to = 900 }] }]\n",
}


@pytest.mark.parametrize("axes", TABLES.values(), ids=TABLES.keys())
def test_table_valued_axis_is_refused_not_a_type_error(axes):
    with pytest.raises(ConfigError, match="set axis") as exc:
        parse_sweep(HEAD + axes)
    assert exc.value.field.startswith("axes.")


def test_profiles_as_a_set_axis_work():
    axes = (
        "[axes.ramp]\n"
        "slow = { control.speed_ref_rpm = { initial = 0, changes = [{ at = 0.01, to = 600 }] } }\n"
        "fast = { control.speed_ref_rpm = { initial = 0, changes = [{ at = 0.01, to = 900 }] } }\n"
    )
    sweep = parse_sweep(HEAD + axes)
    ends = [sweep.scenario(i).control.speed_ref_rpm.points[-1][1] for i in range(2)]
    assert ends == [600.0, 900.0]


def test_cli_exit_2_one_line(tmp_path):
    """Through ``main`` in this process (``data.inprocess``: a traceback is an exception, a
    warning a line of stderr); tests/sweep/test_sweep.py runs a bad sweep file through the
    real command."""
    f = tmp_path / "twins.toml"
    f.write_text(HEAD + TWINS["a variant's R2_ohm under R2_ratio"][0])
    proc = imdrive_here("sweep", f, "--out", tmp_path / "s", "--dry-run", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "R2_ratio" in lines[0] and "variant" in lines[0]
    assert not (tmp_path / "s").exists()
