"""``imdrive warm-up``'s jobs cover the MRAS drive with every set of optional blocks."""

import pytest

from imdrive.cli.warmup import FEATURE_SETS, jobs, run_job
from imdrive.config.scenario import Scenario
from imdrive.errors import ConfigError
from imdrive.kernels import features
from imdrive.run.build import build_arrays


def test_each_feature_set_is_a_job_and_its_preset_compiles_that_set():
    names = jobs()
    assert names[0] == "drive:mras"
    assert "batch:all" in names  # a batch of every estimator: their union's one kernel
    wanted = {"r2": features.GROUPS[0], "realistic": features.GROUPS[1]}
    wanted["r2+realistic"] = features.GROUPS[0] + features.GROUPS[1]
    for key, preset in FEATURE_SETS.items():
        assert f"drive:mras:{key}" in names
        compiled = build_arrays(Scenario.read(preset)).params.features.dtype.names[1:]
        assert set(compiled) == set(wanted[key]), preset


def test_an_unknown_set_is_refused_by_name():
    with pytest.raises(ConfigError, match="drive:mras:warp"):
        run_job("drive:mras:warp")
    with pytest.raises(ConfigError, match="batch:mras:warp"):
        run_job("batch:mras:warp")
