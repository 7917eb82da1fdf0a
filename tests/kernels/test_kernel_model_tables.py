"""The controller's tables (kernels/model.py): the cheaper evaluations give the same numbers.

The flux reference needs only the magnetising curve's secant, so it is computed without the
incremental inductance's derivative (:func:`magnetising_secant`); a flat cell of a linear table
(the inverter-error table past its first node) is read without a division. Both must give bit
for bit what the full evaluation gives: the realistic drives' runs depend on every bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from imdrive.config.scenario import Scenario
from imdrive.kernels.model import (
    magnetising_inductances,
    magnetising_secant,
    reference_magnetising,
    table_interp,
)
from imdrive.run.build import build_arrays

#: A table with cells of different widths (the commissioned presets' nodes are nearly uniform).
UNEVEN = (
    "controller_model.magnetising_psi_Wb=[0.05, 0.2, 0.26, 0.4, 0.45, 0.6, 0.9]",
    "controller_model.magnetising_Lm_H=[0.077, 0.0769, 0.0767, 0.074, 0.071, 0.06, 0.04]",
)


def _model(overrides=()):
    return build_arrays(Scenario.read("sensorless-realistic", list(overrides))).state0.model[0]


def _flux_points(m) -> np.ndarray:
    """Fluxes below, at, between and past the table's nodes, Wb."""
    nodes = np.asarray(m["sat_psi"][: m["sat_n"]])
    between = np.linspace(0.0, 1.3 * nodes[-1], 997)
    return np.concatenate([nodes, np.nextafter(nodes, 0.0), between])


@pytest.mark.parametrize("overrides", [(), UNEVEN], ids=["commissioned", "uneven"])
def test_secant_alone_is_the_secant_of_the_full_evaluation_bit_for_bit(overrides):
    m = _model(overrides)
    assert m["sat_n"] > 0
    for psi in _flux_points(m):
        assert magnetising_secant(m, psi) == magnetising_inductances(m, psi)[0], psi


@pytest.mark.parametrize("overrides", [(), UNEVEN], ids=["commissioned", "uneven"])
def test_flux_reference_secant_is_the_full_evaluation_at_its_flux(overrides):
    m = _model(overrides)
    M, Ll2 = m["M_hat"], m["Ll2_hat"]
    for psi_ref in (0.0, 0.2, 0.45, 0.52, 0.8):
        for i_q in (-30.0, -4.0, 0.0, 3.3, 12.0):
            pm_q = M * Ll2 / (Ll2 + M) * i_q
            want, _ = magnetising_inductances(m, (psi_ref * psi_ref + pm_q * pm_q) ** 0.5)
            assert reference_magnetising(m, psi_ref, i_q) == want


def test_flat_cells_of_a_linear_table_read_as_with_the_division():
    xs = np.array([0.0, 0.2, 5.0, 33.224, 40.0])
    ys = np.array([0.0, 7.22254, 7.22254, 7.22254, 9.0])
    for x in np.concatenate([np.linspace(0.0, 45.0, 1001), xs]):
        y, slope = table_interp(x, xs, ys, len(xs))
        if x <= xs[0] or x >= xs[-1]:
            continue
        k = int(np.searchsorted(xs, x, side="right")) - 1
        want = (ys[k + 1] - ys[k]) / (xs[k + 1] - xs[k])
        assert np.signbit(slope) == np.signbit(want) and slope == want, x
        assert y == ys[k] + want * (x - xs[k]), x
    # a cell whose difference is -0.0 keeps the division's sign of zero
    y, slope = table_interp(0.5, np.array([0.0, 1.0]), np.array([0.0, -0.0]), 2)
    assert slope == 0.0 and np.signbit(slope) and y == 0.0 and not np.signbit(y)
