"""Configuration: machine, inverter, profiles, scenario, overrides and presets.

Pure Python: this layer never imports numba nor the kernels.
"""

from imdrive.config.machine import MachineParams, machine_preset, machine_presets
from imdrive.config.presets import preset_names, preset_text, scenario_text
from imdrive.config.profiles import Profile, parse_profile
from imdrive.config.scenario import Scenario

__all__ = [
    "MachineParams",
    "Profile",
    "Scenario",
    "machine_preset",
    "machine_presets",
    "parse_profile",
    "preset_names",
    "preset_text",
    "scenario_text",
]
