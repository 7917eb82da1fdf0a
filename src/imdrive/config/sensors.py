"""Settings of the current sensors' imperfections (section ``[sensor]``)."""

from __future__ import annotations

from typing import Annotated

from imdrive.config.validation import Float, Int, setting, settings


@settings("sensor")
class SensorSettings:
    """Sensor imperfections (``[sensor]``).

    Two phase-current sensors (a and b; ``i_c = -i_a - i_b``), each with gain, offset, Gaussian
    noise (seeded) and ADC quantisation, plus the DC-link voltage sensor's gain; and DC
    offsets on the α and β currents. Models in :mod:`imdrive.kernels.sensors`.
    """

    i_offset_alpha_A: Annotated[Float, setting("DC offset of the measured α current", "A")] = 0.0
    i_offset_beta_A: Annotated[Float, setting("DC offset of the measured β current", "A")] = 0.0
    gain_a: Annotated[Float, setting("gain of the phase-a current sensor", gt=0.0)] = 1.0
    gain_b: Annotated[Float, setting("gain of the phase-b current sensor", gt=0.0)] = 1.0
    offset_a_A: Annotated[Float, setting("offset of the phase-a current sensor", "A")] = 0.0
    offset_b_A: Annotated[Float, setting("offset of the phase-b current sensor", "A")] = 0.0
    noise_rms_A: Annotated[
        Float, setting("rms of the Gaussian noise of each current sensor", "A", ge=0.0)
    ] = 0.0
    adc_bits: Annotated[
        Int | None,
        setting("ADC resolution of the current sensors", "bit", ge=2, le=32, default_doc="none"),
    ] = None
    adc_range_A: Annotated[
        Float | None,
        setting(
            "ADC full scale of the current sensors (±); the absolute twin of adc_range_pu",
            "A",
            gt=0.0,
            derived=True,
        ),
    ] = None
    adc_range_pu: Annotated[
        Float | None,
        setting(
            "ADC full scale of the current sensors (±) in per-unit of the machine's rated peak "
            "current (instead of adc_range_A)",
            gt=0.0,
            default_doc="unset: adc_range_A",
        ),
    ] = None
    seed: Annotated[
        Int,
        setting(
            "seed of the sensor noise (same seed, same run; a 63-bit integer)",
            ge=0,
            le=2**63 - 1,
        ),
    ] = 0
    vdc_gain: Annotated[
        Float,
        setting(
            "gain of the DC-link voltage sensor: the controller turns volts into duty cycles "
            "with gain × Vdc",
            gt=0.0,
        ),
    ] = 1.0

    @property
    def per_phase(self) -> bool:
        """Whether the per-phase current-sensor model is needed (anything not ideal)."""
        return (
            self.gain_a != 1.0
            or self.gain_b != 1.0
            or self.offset_a_A != 0.0
            or self.offset_b_A != 0.0
            or self.noise_rms_A != 0.0
            or self.adc_bits is not None
        )
