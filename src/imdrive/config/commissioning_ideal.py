"""What an ideal commissioning run identifies: the controller's tables from the plant's model
(``controller_model.ideal = true``; :mod:`imdrive.analysis.commissioning` prints them).

A real drive identifies its magnetising curve in a rotating no-load test at several flux levels
and its inverter's voltage error in a standstill DC test at several currents (IEC 60034-28
describes the no-load test; the DC test with the inverter's error as a function of current is
the standard self-commissioning practice). This module computes what such tests find on the
simulated plant when they are *ideal* -- no noise, no sensor error, every test settled -- from
the plant's own models:

* **magnetising curve**: the plant's curve (:mod:`imdrive.kernels.saturation`)
  ``i_m = (psi_m/Lm0)(1 + (psi_m/psi_sat)^S)`` sampled at magnetising fluxes
  ``flux_pu`` times the rated flux (default 0.2-1.4 in steps of 0.05: the no-load test's flux
  levels, denser than a real drive's so the incremental inductance between them is accurate
  to about 1 %), ``Lm = psi_m/i_m`` at each;
* **inverter error**: the loss per phase the dead time and the device drop cause,
  ``u = t_d f_sw Vdc + V_drop`` for a current of either sign (:mod:`imdrive.kernels.inverter`:
  one delayed edge per carrier period and leg, the drop of the conducting device), reached at
  the current ``inverter.sign_band_A`` (below it the current's ripple and the sensors' noise
  make the sign uncertain; the DC test's smallest current) and constant beyond;
* **current sensors' relative gain**: ``g_b/g_a`` of the plant's two phase sensors (the DC
  test finds it from the beta voltage, :mod:`imdrive.commission.dc`), derived at use by
  :func:`current_gain_b_per_a` rather than stored with the tables.

Values are rounded to 6 significant digits, as the tables a preset states: the realistic
presets' tables were written by this function, and ``ideal = true`` gives them to the bit.
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from imdrive.config.perunit import sign_band_A
from imdrive.errors import ConfigWarning

#: The no-load test's flux levels, per unit of the rated flux.
FLUX_PU = tuple(np.round(np.arange(0.2, 1.4001, 0.05), 4))


def plant_magnetising_curve(sc) -> tuple[float, float, float]:
    """``(Lm0, psi_sat, S)`` of the plant's magnetising curve (``[plant.saturation]``; the
    defaults through the machine's ``M_H`` at its rated flux, as the plant builds them)."""
    return sc.plant.saturation.curve(sc.machine)


def plant_secant_inductance(sc, psi_m) -> np.ndarray:
    """The plant's secant magnetising inductance ``Lm(psi_m) = Lm0/(1 + (psi_m/psi_sat)^S)``,
    H (``M_H`` everywhere without saturation)."""
    psi_m = np.asarray(psi_m, dtype=float)
    if not sc.plant.saturation.enabled:
        return np.full_like(psi_m, sc.machine.M_H)
    Lm0, psi_sat, S = plant_magnetising_curve(sc)
    return Lm0 / (1.0 + (psi_m / psi_sat) ** S)


def plant_inverter_error(sc) -> float:
    """The loss per phase of the plant's inverter for a current well away from zero, V:
    ``t_d f_sw Vdc + V_drop``."""
    inv = sc.inverter
    return inv.dead_time_s * inv.switching_frequency_Hz * inv.Vdc_V + inv.device_drop_V


def ideal_commissioning(sc, flux_pu=FLUX_PU) -> dict[str, list[float]]:
    """The ``[controller_model]`` tables an ideal commissioning identifies on ``sc``'s plant.

    Returns the section's keys: ``magnetising_psi_Wb``, ``magnetising_Lm_H`` (omitted without
    saturation: the constant ``M̂`` is then the plant's), ``inverter_error_i_A`` and
    ``inverter_error_u_V`` (omitted when the inverter loses nothing). The sensors' relative
    gain is :func:`current_gain_b_per_a`.
    """
    out: dict[str, list[float]] = {}
    if sc.plant.saturation.enabled:
        psi = np.asarray(flux_pu, dtype=float) * sc.machine.rated_flux_Wb
        out["magnetising_psi_Wb"] = [float(f"{v:.6g}") for v in psi]
        out["magnetising_Lm_H"] = [float(f"{v:.6g}") for v in plant_secant_inductance(sc, psi)]
    u = plant_inverter_error(sc)
    if u > 0.0:
        band = sign_band_A(sc)
        i_top = 2.0 * sc.control.current_limit_A if sc.control.current_limit_A else 0.0
        i_top = max(i_top, 4.0 * sc.machine.rated_current_A, 2.0 * band)
        out["inverter_error_i_A"] = [0.0, float(f"{band:.6g}"), float(f"{i_top:.6g}")]
        out["inverter_error_u_V"] = [0.0, float(f"{u:.6g}"), float(f"{u:.6g}")]
    return out


#: The ``[controller_model]`` tables (:func:`ideal_commissioning` gives some of them).
TABLE_KEYS = ("magnetising_psi_Wb", "magnetising_Lm_H", "inverter_error_i_A", "inverter_error_u_V")


def resolve_ideal(sc) -> None:
    """``controller_model.ideal = true``: set the scenario's tables to
    :func:`ideal_commissioning` of its plant (called while the scenario is validated, after
    the machine's defaults). Given tables that differ are replaced, with a warning. The
    sensors' relative gain is derived at use (:func:`current_gain_b_per_a`)."""
    cm = sc.controller_model
    if not cm.ideal:
        return
    ideal = ideal_commissioning(sc)
    tables = {k: tuple(ideal.get(k, ())) for k in TABLE_KEYS}
    given = {k: tuple(getattr(cm, k)) for k in TABLE_KEYS}
    if any(given.values()) and given != tables:
        warnings.warn(
            ConfigWarning(
                "controller_model.ideal",
                "the tables given are replaced by those an ideal commissioning identifies on "
                "this plant (set ideal = false to keep them)",
            ),
            stacklevel=4,
        )
    object.__setattr__(sc, "controller_model", replace(cm, **tables))


def current_gain_b_per_a(sc) -> float:
    """The current sensors' relative gain ``g_b/g_a`` the controller's calibration uses:
    ``controller_model.current_gain_b_per_a`` when given (kept with ``ideal = true``: 1 runs
    the drive uncalibrated), else the plant's with ``ideal = true`` (derived here, at use,
    so that it follows a change of the sensors' gains), else 1."""
    cm = sc.controller_model
    if cm.current_gain_b_per_a is not None:
        return cm.current_gain_b_per_a
    return sc.sensor.gain_b / sc.sensor.gain_a if cm.ideal else 1.0
