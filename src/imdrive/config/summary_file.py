"""Reading a run's ``summary.json``: the file checked before it is opened, and the scenario it
records (to run it again, ``imdrive run out/x/summary.json``, or to compare it).

Both ``Scenario.read`` and :mod:`imdrive.run.compare` read summaries here, so a file that is not
one is refused the same way everywhere.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

from imdrive.config.plugins import changed_modules, resolve_plugin_paths
from imdrive.errors import ConfigError, ConfigWarning

#: the largest ``summary.json`` read (one holds a scenario and a few hundred values: ~20 kB)
MAX_SUMMARY_BYTES = 64 * 1024**2


def read_summary_json(path, field: str = "scenario") -> dict:
    """A result's ``summary.json`` as a dict, or one :class:`~imdrive.errors.ConfigError`.

    Refused, naming ``path``: what is not a regular file (a FIFO would block the read, a link
    to ``/dev/zero`` would never end), more than :data:`MAX_SUMMARY_BYTES`, not UTF-8, not
    JSON, nested too deeply, or without a ``"scenario"`` table.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    field : str
        The field the error names (``"scenario"``, ``"run"``).

    Returns
    -------
    dict
        The whole summary.
    """
    from imdrive.config.user_files import read_user_file

    raw = read_user_file(path, field, MAX_SUMMARY_BYTES, "summary.json")
    path = Path(path)
    try:
        data = json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError:
        raise ConfigError(field, f"{path}: not UTF-8 text (summary.json is UTF-8 JSON)") from None
    except RecursionError:
        raise ConfigError(field, f"{path}: JSON nested too deeply to read") from None
    except ValueError as exc:
        raise ConfigError(field, f"{path} is not valid JSON: {exc}") from None
    if not isinstance(data, dict) or not isinstance(data.get("scenario"), dict):
        raise ConfigError(field, f'{path} holds no "scenario" table (not an imdrive summary)')
    return data


def summary_scenario(path) -> dict:
    """The scenario table a ``summary.json`` records, its plug-in paths made absolute from the
    file's folder; a :class:`~imdrive.errors.ConfigWarning` for each module whose sha256 differs
    from the one recorded.

    Parameters
    ----------
    path : str or pathlib.Path
        The ``summary.json``.

    Returns
    -------
    dict
        Its ``"scenario"`` table (TOML-shaped), not yet validated.
    """
    data = read_summary_json(path)
    folder = Path(path).parent
    recorded = data.get("plugins")
    if isinstance(recorded, dict):  # a module's path is relative to the result's folder
        probe = {"plugins": {"modules": list(recorded)}}
        resolve_plugin_paths(probe, folder)
        recorded = dict(zip(probe["plugins"]["modules"], recorded.values(), strict=True))
    data = data["scenario"]
    resolve_plugin_paths(data, folder)
    from imdrive.config.machine import resolve_machine_file

    resolve_machine_file(data, folder)
    for spec in changed_modules(recorded):
        warnings.warn(
            ConfigWarning(
                "plugins.modules",
                f"{spec} has changed since the run {path} records (its sha256 differs): "
                "this rerun uses the module as it is now",
            ),
            stacklevel=4,
        )
    return data


def portable_summary(summary: dict, folder) -> dict:
    """``summary`` as a result folder keeps it: no absolute path of the machine it ran on.

    A result is sent to colleagues; the sender's absolute paths (``/home/alice/...``) are
    not theirs to read (issue 40, class 15). ``[machine] file`` is dropped from the scenario,
    whose ``[machine]`` table holds every value the file gave, so a rerun needs no file;
    each plug-in module's path (in ``[plugins] modules`` and the ``"plugins"`` hashes) is
    made relative to ``folder``, where :func:`summary_scenario` resolves it again. Dotted
    module names stay as they are.

    Parameters
    ----------
    summary : dict
        A summary (a run's, a replay's, a commissioning's) with its ``"scenario"`` table.
    folder : str or os.PathLike
        The folder the summary is written in (or a staging folder beside it).

    Returns
    -------
    dict
        A copy; ``summary`` is left as it was.
    """
    import copy

    out = dict(summary)
    scenario = summary.get("scenario")
    if isinstance(scenario, dict):
        out["scenario"] = portable_scenario(copy.deepcopy(scenario), folder)
    hashes = summary.get("plugins")
    if isinstance(hashes, dict):
        out["plugins"] = {_relative(k, folder): v for k, v in hashes.items()}
    return out


def portable_scenario(data: dict, folder) -> dict:
    """A scenario table (changed in place and returned) without absolute paths: the machine
    file dropped (its values are in the table), plug-in files relative to ``folder``."""
    machine = data.get("machine")
    if isinstance(machine, dict) and machine.get("file") is not None:
        machine["file"] = None
    plugins = data.get("plugins")
    if isinstance(plugins, dict) and isinstance(plugins.get("modules"), list | tuple):
        plugins["modules"] = [_relative(m, folder) for m in plugins["modules"]]
    return data


def _relative(spec, folder):
    """A plug-in module's path relative to ``folder``; a dotted name as it is."""
    import os

    from imdrive.config.plugins import _is_path

    if not isinstance(spec, str) or not _is_path(spec) or not os.path.isabs(spec):
        return spec
    try:
        return os.path.relpath(spec, os.path.abspath(folder))
    except ValueError:  # another drive (Windows): the name alone
        return os.path.basename(spec)
