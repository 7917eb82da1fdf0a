"""Defaults first set in SI on the paper's Table IV machine, scaled to the scenario's machine
(:func:`table_iv_scaled`), for the modules that resolve settings in per-unit of the machine
(:mod:`imdrive.config.perunit`, :mod:`imdrive.config.scaled`,
:mod:`imdrive.config.compensator_gains`).
"""

from __future__ import annotations


def table_iv_scaled(value: float, base, machine) -> float:
    """A default first set in SI on the Table IV machine, scaled to ``machine``:
    ``value x base(machine) / base(Table IV)``, exactly ``value`` on Table IV.

    Parameters
    ----------
    value : float
        The default on Table IV, SI.
    base : callable
        The machine's quantity the setting scales with (``rated_peak_current_A``).
    machine : MachineParams
        The scenario's machine.
    """
    from imdrive.config.machine import machine_preset

    return value * (base(machine) / base(machine_preset("paper-table-iv")))
