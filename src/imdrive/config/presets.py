"""The built-in scenario presets (TOML files in ``imdrive/config/presets``)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from imdrive.errors import ConfigError


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
    p = Path(preset_or_path)
    try:
        is_file = p.is_file()
    except (OSError, ValueError) as exc:  # a name too long, a NUL byte: not a usable path
        raise ConfigError("scenario", f"not a usable file path: {exc}") from None
    if is_file:
        try:
            return p.read_text(encoding="utf-8-sig")  # a byte-order mark is not part of TOML
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigError("scenario", f"cannot read {p}: {exc}") from None
    raise ConfigError(
        "scenario", f"{preset_or_path!r} is neither a preset (see 'imdrive presets') nor a file"
    )
