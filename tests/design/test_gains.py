"""The torque constant of field-oriented control (design/gains.py) against the steady state of
the T-equivalent circuit (analysis/circuit.py): the circuit's torque equals ``k_t i_q`` with
``i_q`` the stator current's component in quadrature with the rotor flux."""

import numpy as np
import pytest

from imdrive.analysis.circuit import equivalent_circuit
from imdrive.config.machine import machine_preset
from imdrive.design.gains import torque_constant


@pytest.mark.parametrize("name", ["paper-table-iv", "krause-500hp", "aalto-2.2kw"])
@pytest.mark.parametrize("slip", [0.03, -0.02])
def test_torque_is_k_t_times_the_quadrature_current(name, slip):
    m = machine_preset(name)
    L2 = m.M_H + m.Ll2_H
    ss = equivalent_circuit(m, m.rated_voltage_V, m.rated_frequency_Hz, slip)
    psi_r = m.M_H * ss.I1 + L2 * ss.I2  # rotor-flux phasor, peak, Wb
    i_q = np.imag(ss.I1 * np.conj(psi_r)) / abs(psi_r)  # in quadrature with it, A
    k_t = torque_constant(m.pole_pairs, m.M_H, L2, abs(psi_r))
    assert k_t * i_q == pytest.approx(ss.torque_Nm, rel=1e-9)
