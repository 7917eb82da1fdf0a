"""The defaults that depend on the scenario as a whole, as one scenario resolves them: what
``imdrive show PRESET --all`` prints beside an unset setting (``Scenario.to_toml``).
"""

from __future__ import annotations

from imdrive.config.current_control import current_controller
from imdrive.config.field_weakening import field_weakening_on
from imdrive.config.mras_bandwidth import mras_bandwidth_Hz
from imdrive.config.r1_standstill import r1_standstill_levels
from imdrive.config.speed_gain import speed_gain_flux_scaling


def resolved_defaults(sc) -> dict[str, object]:
    """Dotted key -> the value an unset scenario-dependent setting takes in ``sc``.

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    dict
        ``control.field_weakening`` (:func:`~imdrive.config.field_weakening.field_weakening_on`),
        ``control.current_controller``, ``control.speed_gain_flux_scaling``,
        ``mras.R1_standstill_levels``, ``mras.bandwidth_Hz``
        (:func:`~imdrive.config.mras_bandwidth.mras_bandwidth_Hz`), ``mras.acceleration_tracking``
        (with the MRAS in the loop), and with the compensator on, its unset machine-dependent
        settings (:mod:`imdrive.config.compensator_gains`), and with the injection on, its
        frequency; empty for an open-loop drive.
    """
    if sc.drive.mode != "vector":
        return {}
    out = {
        "control.field_weakening": field_weakening_on(sc),
        "control.current_controller": current_controller(sc),
        "control.speed_gain_flux_scaling": speed_gain_flux_scaling(sc),
        "mras.R1_standstill_levels": r1_standstill_levels(sc),
        "mras.bandwidth_Hz": mras_bandwidth_Hz(sc),
    }
    from imdrive.config.perunit import resolve

    r = resolve(sc)
    if sc.control.speed_feedback == "mras":
        from imdrive.config.estimators import mras_type2

        T2_hat = (r.Ll2_hat + r.M_hat) / r.R2_hat
        out["mras.acceleration_tracking"] = mras_type2(sc, sc.mras, T2_hat)
    if sc.compensator.enabled:
        for key, value in (
            ("G_CR_ohm", r.G_CR),
            ("gain_E_per_Wb", r.gain_E),
            ("gate_speed_rpm", r.gate_speed_rpm),
            ("gate_iq_A", r.gate_iq_A),
            ("gate_band_Hz", r.gate_band),
        ):
            out[f"compensator.{key}"] = float(value)
    if r.inj_amp > 0.0 and sc.injection.frequency_pu is None:
        out["injection.frequency_Hz"] = float(r.inj_f1)
    return out
