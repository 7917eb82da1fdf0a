"""Self-commissioning: the drive identifies its machine and inverter (an identification run).

:func:`commission` runs, on the simulated drive with every non-ideality of the scenario on,
the tests an industrial drive runs before first use, seeing only what a drive sees (its
measured currents, commanded voltages, DC link and speed estimate): a standstill DC test
(:mod:`~imdrive.commission.dc`: R1, the inverter's voltage-error table), a rotating no-load
test (:mod:`~imdrive.commission.noload`: L1, the magnetising curve), a standstill AC test
(:mod:`~imdrive.commission.ac`: sigma L1, R2) and an acceleration test
(:mod:`~imdrive.commission.inertia`: J). docs/commissioning.md describes them.
"""

from __future__ import annotations

from imdrive.commission.base import CommissioningFailed
from imdrive.commission.identify import CommissioningResult, identify, write_outputs

__all__ = ["CommissioningFailed", "CommissioningResult", "commission"]


def commission(scenario, out=None) -> CommissioningResult:
    """Identify the machine and inverter of ``scenario`` (see the module docstring).

    Parameters
    ----------
    scenario : Scenario
        A field-oriented drive (``drive.mode = "vector"``).
    out : str or pathlib.Path, optional
        Folder for ``summary.json``, ``identified.toml`` and the figures (none written if
        unset, nor if a test fails).

    Returns
    -------
    CommissioningResult

    Raises
    ------
    ConfigError
        A scenario commissioning cannot handle (an open-loop drive, a DC link too low).
    CommissioningFailed
        A test that did not converge (naming it and why).
    """
    res = identify(scenario)
    if out is not None:
        write_outputs(scenario, res, out)
    return res
