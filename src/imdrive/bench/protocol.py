"""The test protocol: which estimator configurations, which scenarios, on which drive.

Every run is a preset (``sensorless`` for the average drive, ``sensorless-realistic`` for the
realistic one: switching inverter with dead time, one-period delay, imperfect sensors,
saturation) with the overrides of its *estimator* and of its *case*. The flux is built for
0.5 s at standstill, then the reference ramps over 1 s; the metrics' windows are in
:mod:`imdrive.bench.metrics`.

Estimator configurations (:data:`ESTIMATORS`): the speed estimator and who adapts R̂2.

Cases (:data:`CASES`): steady state at 1000/150/30 rpm with rated load, load steps, a speed
reversal through zero, low-speed regeneration (rated driving load at 40 rpm: stator
frequency near 1 rad/s), a thermal drift of R1 and R2 (+30 % over 4 s), an initial R̂2 error
(-20 %), R̂1 error (+30 %) and M̂ error (-10 %).
"""

from __future__ import annotations

from dataclasses import dataclass

RATED_LOAD_NM = 12.0
DRIVES = {"average": "sensorless", "realistic": "sensorless-realistic"}

_COMP_ON = [
    "compensator.enabled=true",
    "compensator.t_on_s=3.0",
    "compensator.period_s=0.01",
    "compensator.gain_E_per_Wb=1e6",
    "compensator.gain_DE_per_Wb=1e6",
    "compensator.G_CR_ohm=0.001",
    "compensator.R2_min_ohm=0.408",
    "compensator.R2_max_ohm=1.224",
]

#: estimator configuration -> overrides
ESTIMATORS: dict[str, list[str]] = {
    "mras": ['control.speed_feedback="mras"'],
    "mras+fuzzy": ['control.speed_feedback="mras"', *_COMP_ON],
    "reactive-mras": ['control.speed_feedback="reactive-mras"'],
    "afo": ['control.speed_feedback="afo"'],
    "afo+R2": [
        'control.speed_feedback="afo"',
        'estimator.R2_adaptation="afo"',
        "flux_injection.amplitude=0.1",
        "flux_injection.frequency_Hz=2.0",
    ],
    "afo+R1": ['control.speed_feedback="afo"', "afo.R1_adaptation=true"],
    "ekf": ['control.speed_feedback="ekf"'],
    "ekf+R2": [
        'control.speed_feedback="ekf"',
        'estimator.R2_adaptation="ekf"',
        "flux_injection.amplitude=0.1",
        "flux_injection.frequency_Hz=2.0",
    ],
    "smo-mras": ['control.speed_feedback="smo-mras"'],
}


def _ramp(rpm: float, at: float = 0.5, over: float = 1.0) -> str:
    return f"control.speed_ref_rpm={{initial=0, changes=[{{at={at}, to={rpm}, over={over}}}]}}"


def _load(*steps) -> str:
    ch = ", ".join(f"{{at={t}, to={v}}}" for t, v in steps)
    return f"load.torque_Nm={{initial=0, changes=[{ch}]}}"


@dataclass(frozen=True)
class Case:
    """One scenario of the protocol.

    Attributes
    ----------
    overrides : tuple[str, ...]
        Scenario overrides (``key=value``, as ``imdrive run --set``) on top of the drive's
        and the estimator's.
    t_end_s : float
        Length of the run, s.
    t_eval_s : float
        Start of the window of the RMS and lost-control metrics, s (the event under test).
    """

    overrides: tuple[str, ...]
    t_end_s: float
    t_eval_s: float


L = RATED_LOAD_NM
#: case name -> Case
CASES: dict[str, Case] = {
    "steady-1000": Case((_ramp(1000), _load((2.0, L))), 4.0, 2.0),
    "steady-150": Case((_ramp(150), _load((2.0, L))), 4.0, 2.0),
    "steady-30": Case((_ramp(30), _load((2.0, L))), 4.0, 2.0),
    "load-steps": Case((_ramp(500), _load((2.0, L), (3.0, 0.0), (4.0, L))), 5.0, 2.0),
    "reversal": Case(
        (
            "control.speed_ref_rpm={initial=0, changes=[{at=0.5, to=300, over=0.5}, "
            "{at=2.0, to=-300, over=1.0}]}",
            _load((1.5, 0.25 * L)),
        ),
        4.5,
        2.0,
    ),
    "regeneration-40": Case((_ramp(40), _load((2.0, -L))), 5.0, 2.0),
    "thermal-drift": Case(
        (
            _ramp(500),
            _load((2.0, L)),
            "plant.R1_scale={initial=1, changes=[{at=4.0, to=1.3, over=4.0}]}",
            "plant.R2_scale={initial=1, changes=[{at=4.0, to=1.3, over=4.0}]}",
        ),
        10.0,
        2.0,
    ),
    "R2-error": Case((_ramp(500), _load((2.0, L)), "estimator.R2_ohm=0.6528"), 8.0, 2.0),
    "R1-error": Case((_ramp(150), _load((2.0, L)), "estimator.R1_ohm=0.5655"), 4.0, 2.0),
    "M-error": Case((_ramp(150), _load((2.0, L)), "estimator.M_H=0.06237"), 4.0, 2.0),
}

QUICK_ESTIMATORS = ("mras", "reactive-mras", "afo", "ekf")
QUICK_CASES = ("steady-1000", "steady-150", "R1-error")


@dataclass(frozen=True)
class Run:
    """One run of the protocol: an estimator configuration on a case and a drive.

    Attributes
    ----------
    estimator : str
        A key of :data:`ESTIMATORS`.
    case : str
        A key of :data:`CASES`.
    drive : str
        A key of :data:`DRIVES` (``average`` or ``realistic``).
    """

    estimator: str
    case: str
    drive: str


def protocol(quick: bool = False, estimators=None) -> list[Run]:
    """Every run of the protocol.

    Parameters
    ----------
    quick : bool
        Only a small subset on the average drive (for CI).
    estimators : iterable of str, optional
        The estimator configurations to compare (default: every key of :data:`ESTIMATORS`;
        a configuration of your own: :func:`scenario`'s ``estimators``).

    Returns
    -------
    list of Run
        Drives, then cases, then estimators (the last varying fastest).
    """
    if quick:
        names = QUICK_ESTIMATORS if estimators is None else tuple(estimators)
        return [Run(e, c, "average") for c in QUICK_CASES for e in names]
    names = ESTIMATORS if estimators is None else tuple(estimators)
    return [Run(e, c, d) for d in DRIVES for c in CASES for e in names]


def scenario(run: Run, estimators: dict | None = None):
    """The scenario of one run.

    Parameters
    ----------
    run : Run
        Estimator, case and drive.
    estimators : dict, optional
        Estimator configurations beside :data:`ESTIMATORS`: name -> overrides (e.g. a
        plug-in estimator: ``{"mine": ['control.speed_feedback="mine"',
        'plugins.modules=["my_module.py"]']}``).

    Returns
    -------
    Scenario
        The validated :class:`~imdrive.config.scenario.Scenario`.
    """
    from imdrive.config.scenario import Scenario

    case = CASES[run.case]
    configs = {**ESTIMATORS, **(estimators or {})}
    if run.estimator not in configs:
        from imdrive.errors import ConfigError

        raise ConfigError("estimators", f"no estimator configuration {run.estimator!r}")
    ov = [
        *configs[run.estimator],
        *case.overrides,
        f"simulation.t_end_s={case.t_end_s}",
        "simulation.log_every=10",
        f'name="{run.estimator}.{run.case}.{run.drive}"',  # a safe folder name
    ]
    return Scenario.read(DRIVES[run.drive], ov)
