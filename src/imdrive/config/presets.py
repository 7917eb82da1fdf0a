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


def scenario_text(preset_or_path: str) -> str:
    """Text of a preset by name, else of the file at that path."""
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
    return read_user_text(preset_or_path, "scenario", MAX_TOML_BYTES, "scenario file")


def _short(text) -> str:
    text = str(text)
    return text if len(text) <= 120 else f"{text[:60]}... ({len(text)} characters)"
