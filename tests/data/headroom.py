"""The estimation headroom's settings as the injection presets carry them, and their undoing:
shared by the drive tests of the headroom and of the rotor thermal model."""

HEADROOM = (
    "control.field_weakening=true",
    "injection.headroom_voltage=0.88",
    "compensator.gate_voltage=0.99",
)
# the injection preset's headroom undone: the injection backs off from 0.85 of the voltage
# (config/injection_backoff.py: the band follows the estimation headroom)
NO_HEADROOM = {
    "injection.headroom_voltage": None,
    "compensator.gate_voltage": 0.97,
}
