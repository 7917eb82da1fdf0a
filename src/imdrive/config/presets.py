"""The built-in scenario presets (TOML files in ``imdrive/config/presets``)."""

from __future__ import annotations

import os
from importlib import resources

from imdrive.errors import ConfigError

#: The largest scenario or machine file read (B): a hand-written TOML is a few kB.
MAX_TOML_BYTES = 16 * 1024**2


def preset_names() -> list[str]:
    """Names of the built-in scenario presets."""
    root = resources.files("imdrive.config").joinpath("presets")
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def preset_text(name: str) -> str:
    """TOML text of a built-in preset."""
    if name not in preset_names():
        raise ConfigError("preset", f"unknown preset {name!r}; see 'imdrive presets'")
    return resources.files("imdrive.config").joinpath(f"presets/{name}.toml").read_text()


def scenario_text(preset_or_path: str, known=None) -> str:
    """Text of a preset by name, else of the file at that path; with ``known`` (a scenario's
    top-level keys) a file none of whose keys is among them is refused without printing its
    keys or values (:func:`_refuse_a_foreign_file`)."""
    if preset_or_path in preset_names():
        return preset_text(preset_or_path)
    from imdrive.config.user_files import path_form_problem, read_user_text

    problem = path_form_problem(preset_or_path)
    if problem is not None:  # a name too long, a NUL byte: not a usable path
        raise ConfigError("scenario", f"not a usable file path: {problem}")
    if not os.path.lexists(preset_or_path):
        raise ConfigError(
            "scenario",
            f"{_short(preset_or_path)!r} is neither a preset (see 'imdrive presets') nor a file",
        )
    text = read_user_text(preset_or_path, "scenario", MAX_TOML_BYTES, "scenario file")
    if known is not None:
        _refuse_a_foreign_file(preset_or_path, text, known)
    return text


def _refuse_a_foreign_file(path, text: str, known) -> None:
    """Refuse a file none of whose top-level keys is a scenario's, naming neither its keys nor
    its values: a sweep's ``base`` or a command's scenario path may name someone's
    credentials or another program's configuration (issue 40, class 15; as ``machine.file``,
    :func:`imdrive.config.machine.machine_file_values`). A misspelt section is still named by
    the validation that follows."""
    import tomllib

    from imdrive.config.user_files import strange_keys

    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError):
        return  # the scenario's own reader reports it, with the line
    typos, n_foreign = strange_keys(list(data), known)
    if data and n_foreign and not typos and not set(data) & known:
        raise ConfigError(
            "scenario",
            f"{path} is not an imdrive scenario file: none of its {len(data)} keys is a "
            "scenario section or setting (such as [machine], [control] or name)",
        )


def _short(text) -> str:
    text = str(text)
    return text if len(text) <= 120 else f"{text[:60]}... ({len(text)} characters)"
