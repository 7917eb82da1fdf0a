"""What the controller knows of its machine's magnetising curve, of its inverter's voltage
error and of its current sensors' relative gain (section ``[controller_model]``): what a
commissioning (identification) run finds.

Empty tables (the default) keep the constant model: a constant ``M̂`` (``[estimator]``) and the
dead-time feed-forward of ``[control]``. With ``magnetising_*`` the field-oriented controller,
every estimator's flux model and the R2 compensator's injection use ``M̂(ψm)``, the secant
inductance of the table at the magnetising flux the controller believes, and the incremental
inductance of the same curve where a small flux variation matters
(:mod:`imdrive.kernels.model`). With ``inverter_error_*`` the voltage feed-forward and the
voltage the estimators believe applied use the table (:func:`imdrive.kernels.ifoc.inverter_error`).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import model_validator

from imdrive.config.validation import Float, setting, settings
from imdrive.errors import ConfigError

#: Most nodes of each table (the kernels' fixed-size arrays, ``MODEL_TABLE_POINTS``).
TABLE_POINTS = 32

Table = tuple[Float, ...]


def _check_pair(x_key: str, y_key: str, x: tuple, y: tuple) -> None:
    """Same length, none or 2 to :data:`TABLE_POINTS` nodes, ``x`` strictly increasing."""
    if len(x) != len(y):
        raise ConfigError(y_key, f"must have as many values as {x_key} ({len(y)} != {len(x)})")
    if len(x) == 1 or len(x) > TABLE_POINTS:
        raise ConfigError(x_key, f"must have 2 to {TABLE_POINTS} values, or none (got {len(x)})")
    if any(b <= a for a, b in zip(x, x[1:], strict=False)):
        raise ConfigError(x_key, "must be strictly increasing")


@settings("controller_model")
class ControllerModelSettings:
    """The controller's magnetising curve and inverter-error table (``[controller_model]``).

    ``magnetising_Lm_H[k]`` is the secant inductance ``ψm/im`` at the magnetising-flux
    magnitude ``magnetising_psi_Wb[k]``; the controller interpolates the magnetising current
    ``im(ψm)`` between the nodes (monotone cubic Hermite: the secant is exact at the nodes, the
    incremental inductance continuous), a line through the origin below the first node and the
    last slope past the last (kernels/model.py ``magnetising_inductances``).

    ``inverter_error_u_V[k]`` is the voltage the inverter loses on one phase (reference minus
    the period-average pole voltage, referred to the phase) at phase current
    ``inverter_error_i_A[k]``: dead time and device drops. It is odd in the current: give it
    from ``i = 0`` (``u = 0`` there), or over both signs odd-symmetrically; linear between the
    nodes, held past the last. It replaces the feed-forward of
    ``control.dead_time_compensation`` and is subtracted from the commanded voltage the
    estimators use.

    ``current_gain_b_per_a`` is the relative gain ``g_b/g_a`` of the two phase-current sensors
    that the drive's calibration found; the controller multiplies its phase-a reading by
    ``sqrt(g_b/g_a)`` and its phase-b reading by ``sqrt(g_a/g_b)``. A
    relative gain error puts a negative-sequence error into the measured current (a
    ``2 w_s`` ripple in the controller's frame), which the absolute gain error common to both
    sensors does not. ``ideal = true`` takes the tables and this ratio an ideal commissioning
    run identifies on the scenario's plant (:mod:`imdrive.config.commissioning_ideal`).
    """

    magnetising_psi_Wb: Annotated[
        Table,
        setting(
            "magnetising-flux magnitudes of the magnetising-curve table (>= 0, strictly "
            "increasing; 2 to 32 values); empty: the constant M̂ of [estimator]",
            "Wb",
        ),
    ] = ()
    magnetising_Lm_H: Annotated[
        Table,
        setting(
            "the secant magnetising inductance ψm/im at each flux of magnetising_psi_Wb (> 0; "
            "im = ψm/Lm must increase with ψm: a monotone curve)",
            "H",
        ),
    ] = ()
    inverter_error_i_A: Annotated[
        Table,
        setting(
            "phase currents of the inverter-error table (strictly increasing, from 0, or "
            "odd-symmetric about 0; 2 to 32 values); empty: control.dead_time_compensation",
            "A",
        ),
    ] = ()
    inverter_error_u_V: Annotated[
        Table,
        setting(
            "the voltage the inverter loses per phase at each current of inverter_error_i_A "
            "(odd in the current: 0 at 0 A, >= 0 for positive currents)",
            "V",
        ),
    ] = ()
    current_gain_b_per_a: Annotated[
        Float | None,
        setting(
            "the phase-b current sensor's gain relative to phase a's, as the drive's "
            "calibration knows it (the commissioning's DC test measures it from the beta "
            "voltage); the controller scales its phase-a reading by its square root and "
            "divides its phase-b reading by that, so both read with the gains' geometric "
            "mean. Unset: 1 (uncalibrated), or with ideal = true the plant's "
            "ratio; a value given is kept even then (1 runs the drive uncalibrated). With "
            "sensorless-realistic's 0.5 % mismatch uncalibrated the adaptive observer lost "
            "control at 70 rpm regenerating 12 N m; calibrated to within 0.05 % it held all "
            "15 points of 45-100 rpm, -12 ... +12 N m",
            gt=0.0,
            default_doc="unset",
        ),
    ] = None
    ideal: Annotated[
        bool,
        setting(
            "true: the tables and the sensors' relative gain are what an ideal "
            "commissioning run identifies on this "
            "scenario's own plant (config/commissioning_ideal.py), derived when the scenario "
            "is read, so they follow a change of machine or inverter (given tables are "
            "replaced). The realistic presets use it: with Table IV's tables kept, "
            "sensorless-realistic on the Aalto 2.2 kW machine lost control at 0.65 s"
        ),
    ] = False
    saturation: Annotated[
        Literal["table", "none"],
        setting(
            '"table": the controller uses the magnetising curve when one is given; "none": '
            "the constant M̂ even so (to measure what the curve buys)"
        ),
    ] = "table"
    inverter_error: Annotated[
        Literal["table", "none"],
        setting(
            '"table": the feed-forward uses the inverter-error table when one is given; "none": '
            "control.dead_time_compensation even so"
        ),
    ] = "table"

    @model_validator(mode="after")
    def _tables(self):
        psi, Lm = self.magnetising_psi_Wb, self.magnetising_Lm_H
        _check_pair("magnetising_psi_Wb", "magnetising_Lm_H", psi, Lm)
        if psi and psi[0] < 0.0:
            raise ConfigError("magnetising_psi_Wb", "must be >= 0 (a flux magnitude)")
        if any(v <= 0.0 for v in Lm):
            raise ConfigError("magnetising_Lm_H", "must be > 0 (an inductance)")
        i_m = [p / L for p, L in zip(psi, Lm, strict=True)]
        if any(b <= a for a, b in zip(i_m, i_m[1:], strict=False)):
            raise ConfigError(
                "magnetising_Lm_H",
                "must give a current ψm/Lm increasing with ψm (a monotone magnetising curve)",
            )
        i, u = self.inverter_error_i_A, self.inverter_error_u_V
        _check_pair("inverter_error_i_A", "inverter_error_u_V", i, u)
        if i:
            half_i, half_u = inverter_error_half(i, u)
            if half_i[0] != 0.0 or half_u[0] != 0.0:
                raise ConfigError(
                    "inverter_error_i_A",
                    "must start at 0 A with inverter_error_u_V 0 (the error is odd in the "
                    "current), or be odd-symmetric about 0",
                )
            if any(v < 0.0 for v in half_u):
                raise ConfigError(
                    "inverter_error_u_V", "must be >= 0 for positive currents (a loss)"
                )
        return self

    @property
    def uses_magnetising_curve(self) -> bool:
        """Whether the controller's flux model uses the magnetising table."""
        return bool(self.magnetising_psi_Wb) and self.saturation == "table"

    @property
    def uses_inverter_error(self) -> bool:
        """Whether the feed-forward and the believed voltage use the inverter-error table."""
        return bool(self.inverter_error_i_A) and self.inverter_error == "table"


def inverter_error_half(i: tuple, u: tuple) -> tuple[tuple, tuple]:
    """The nodes ``i >= 0`` of an inverter-error table given from 0 or over both signs.

    A table over both signs must be odd-symmetric (``i[k] = -i[n-1-k]``,
    ``u[k] = -u[n-1-k]`` to 1e-9 relative) and contain 0: otherwise a ``ConfigError``.
    """
    if i[0] >= 0.0:
        return tuple(i), tuple(u)
    n = len(i)
    scale_i = max(abs(v) for v in i)
    scale_u = max(max(abs(v) for v in u), 1e-300)
    odd = all(
        abs(i[k] + i[n - 1 - k]) <= 1e-9 * scale_i and abs(u[k] + u[n - 1 - k]) <= 1e-9 * scale_u
        for k in range(n)
    )
    if not odd or n % 2 == 0:
        raise ConfigError(
            "inverter_error_i_A",
            "a table over both signs must be odd-symmetric about a node at 0 A "
            "(i[k] = -i[n-1-k], u[k] = -u[n-1-k])",
        )
    return (0.0, *i[n // 2 + 1 :]), (0.0, *u[n // 2 + 1 :])


def magnetising_table(psi: tuple, Lm: tuple) -> tuple[list, list, list]:
    """The kernels' magnetising-curve table: ``(psi_m, i_m, d i_m / d psi_m)`` at the nodes.

    ``i_m = psi_m / Lm``; the slopes are three-point differences (second-order accurate on a
    smooth curve, one-sided at the ends; Lagrange's weights on the non-uniform grid), limited to
    ``(0, 3 min(secants)]`` either side, the Fritsch–Carlson condition under which the cubic
    Hermite interpolation between the nodes stays monotone (F. N. Fritsch and R. E. Carlson,
    "Monotone piecewise cubic interpolation", SIAM J. Numer. Anal. 17(2), 1980).
    """
    x = [float(v) for v in psi]
    y = [p / L for p, L in zip(psi, Lm, strict=True)]
    n = len(x)
    h = [x[k + 1] - x[k] for k in range(n - 1)]
    sec = [(y[k + 1] - y[k]) / h[k] for k in range(n - 1)]
    if n == 2:
        return x, y, [sec[0], sec[0]]
    d = [0.0] * n
    for k in range(1, n - 1):
        d[k] = (h[k - 1] * sec[k] + h[k] * sec[k - 1]) / (h[k - 1] + h[k])
    d[0] = ((2 * h[0] + h[1]) * sec[0] - h[0] * sec[1]) / (h[0] + h[1])
    d[-1] = ((2 * h[-1] + h[-2]) * sec[-1] - h[-1] * sec[-2]) / (h[-1] + h[-2])
    for k in range(n):
        near = [sec[j] for j in (k - 1, k) if 0 <= j < n - 1]
        d[k] = min(max(d[k], 1e-3 * min(near)), 3.0 * min(near))
    return x, y, d
