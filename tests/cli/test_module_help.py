"""The modules run with ``python -m`` answer ``--help`` with their usage and do nothing else.

Until 2026-11-30 four of them read ``sys.argv`` by hand: ``python -m imdrive.studies.machines
--help`` ran the whole 1344-run grid and wrote it to a file named ``--help``, and
``imdrive.studies.realistic --help`` would have made a folder of that name.
"""

import importlib

import pytest

MODULES = [
    "imdrive.studies.machines",
    "imdrive.studies.realistic",
    "imdrive.run.outputs",
    "imdrive.analysis.commissioning",
]


@pytest.mark.parametrize("name", MODULES)
def test_help_prints_the_usage_and_exits_0(name, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as exc:
        importlib.import_module(name).main(["--help"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.startswith(f"usage: python -m {name}")
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize("name", ["imdrive.studies.machines", "imdrive.analysis.commissioning"])
def test_a_missing_argument_is_a_usage_error(name, capsys):
    with pytest.raises(SystemExit) as exc:
        importlib.import_module(name).main([])
    assert exc.value.code == 2
    assert "required" in capsys.readouterr().err
