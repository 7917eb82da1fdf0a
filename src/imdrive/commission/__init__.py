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
from imdrive.commission.identify import (
    CommissioningResult,
    identify,
    owns_commission_file,
    write_outputs,
)
from imdrive.errors import ConfigError

__all__ = ["CommissioningFailed", "CommissioningResult", "commission"]


def commission(scenario, out=None, force: bool = False) -> CommissioningResult:
    """Identify the machine and inverter of ``scenario`` (see the module docstring).

    Parameters
    ----------
    scenario : Scenario
        A field-oriented drive (``drive.mode = "vector"``).
    out : str or pathlib.Path, optional
        Folder for ``summary.json``, ``identified.toml`` and the figures (none written if
        unset, nor if a test fails). Checked before the identification run by the rule of
        every command that writes a folder (:func:`imdrive._io.output_folder_problem`: not the
        current folder or a parent, not under a file, no other files unless ``force``), and
        replaced as a whole.
    force : bool
        Write into a folder that holds files other than a commissioning result's.

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
    from imdrive.config.scenario import Scenario

    if not isinstance(scenario, Scenario):
        raise ConfigError(
            "scenario",
            f"must be a Scenario (Scenario.read makes one), got {type(scenario).__name__}",
        )
    if out is not None:  # the folder rule, before the identification run starts
        check_output_folder(out, force)
    res = identify(scenario)
    if out is not None:
        write_outputs(scenario, res, out)
    return res


def check_output_folder(out, force: bool = False) -> None:
    """Refuse ``out`` as a commissioning folder by the rule every command that writes a folder
    follows (:func:`imdrive._io.output_folder_problem`).

    Parameters
    ----------
    out : str or os.PathLike
        The folder.
    force : bool
        Allow a folder holding other files.

    Raises
    ------
    ConfigError
        ``out`` (field ``out``) and the problem, in one line.
    """
    import os

    from imdrive._io import output_folder_problem

    if not isinstance(out, str | os.PathLike):
        raise ConfigError("out", f"must be a folder path, got {type(out).__name__}")
    if not os.fspath(out).strip():
        raise ConfigError("out", "is empty: name a folder for the results")
    problem = output_folder_problem(out, owns_commission_file, force, "a commissioning result")
    if problem is not None:
        raise ConfigError("out", problem)
