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
    recorded = data.get("plugins")
    data = data["scenario"]
    resolve_plugin_paths(data, Path(path).parent)
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
