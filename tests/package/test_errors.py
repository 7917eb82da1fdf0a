"""imdrive's errors survive pickling: a run that fails in a worker process (a user's
ProcessPoolExecutor, a notebook's pool) reaches the parent as the same error, field and rule
included, not as a ``BrokenProcessPool`` with a ``TypeError`` from unpickling."""

import pickle
from concurrent.futures import ProcessPoolExecutor

import pytest

from imdrive.errors import ConfigError, ConfigWarning, EnvironmentFailure, SimulationDiverged


@pytest.mark.parametrize(
    "exc",
    [
        ConfigError("injection.frequency_Hz", "must be > 0"),
        ConfigWarning("machine.rated_speed_rpm", "rated slip 14 % is above 10 %"),
        SimulationDiverged(1.25, "stator current"),
        EnvironmentFailure("cannot write out/x: No space left on device"),
    ],
)
def test_round_trip(exc):
    back = pickle.loads(pickle.dumps(exc))
    assert type(back) is type(exc)
    assert str(back) == str(exc)
    assert vars(back) == vars(exc)


def _bad_scenario():
    from imdrive.config import Scenario

    return Scenario.read("sensorless", ["machine.R1_ohm=-1"])


def test_config_error_from_a_worker_process():
    with ProcessPoolExecutor(1) as pool:
        with pytest.raises(ConfigError) as info:
            pool.submit(_bad_scenario).result()
    assert info.value.field.startswith("machine.R1")
