"""The cold-start helper (:mod:`imdrive.run.prefetch`): the blocks it compiles are the ones the
drive loop then loads from the cache instead of compiling, and it starts only when the loop
must compile."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest
from data.compiles import COUNT_COMPILES

from imdrive.config.scenario import Scenario
from imdrive.kernels.engine import run_drive
from imdrive.run import prefetch
from imdrive.run.build import build_arrays, copy_state
from imdrive.run.simulate import new_log, simulate

#: What :func:`imdrive.kernels.prefetch.late_blocks` calls.
LATE = {
    "integrate_segment",
    "log_plant",
    "log_control",
    "log_compensator",
    "inverter_segments",
    "foc_step",
}

RECORDS = textwrap.dedent("""
    import pickle, sys
    from imdrive.config.scenario import Scenario
    from imdrive.run.build import build_arrays
    from imdrive.run.simulate import new_log

    a = build_arrays(Scenario.read(sys.argv[2], ["simulation.t_end_s=0.05"]))
    with open(sys.argv[1], "wb") as f:
        job = ("imdrive.kernels.prefetch", "late_blocks", (a.params, a.state0, new_log(1, a.log)))
        pickle.dump([job], f)  # as start_loop() writes it
""")


def _first_call(sc):
    a = build_arrays(sc)
    log = new_log(3, a.log)
    return a, (a.params, copy_state(a.state0), 0, 0, log[:0], 1, 0, True, new_rec())


def new_rec():
    import numpy as np

    from imdrive.kernels.recording import RECORDING

    return np.zeros(0, dtype=RECORDING)


#: As RECORDS, for a batch of one group of drives of the estimators ``sys.argv[3]`` (comma
#: separated): the jobs as start_batch() writes them.
RECORDS_BATCH = textwrap.dedent("""
    import pickle, sys
    from imdrive.config.scenario import Scenario
    from imdrive.run.batch_groups import first_call, united
    from imdrive.run.build import build_arrays

    groups = {}
    for i, e in enumerate(sys.argv[3].split(",")):
        ov = ["simulation.t_end_s=0.05", f'control.speed_feedback="{e}"']
        a = build_arrays(sc := Scenario.read(sys.argv[2], ov))
        groups.setdefault((1, a.params.est.dtype, a.params.comp.dtype), []).append((i, sc, a))
    ((key, items),) = united(groups).items()
    call = first_call(items, key, 0.5)
    P, S, *_, scratch = call
    with open(sys.argv[1], "wb") as f:
        pickle.dump(
            [
                ("imdrive.kernels.prefetch", "late_blocks", (P, S, scratch[:1])),
                ("imdrive.kernels.batch", "worker_blocks", call),
            ],
            f,
        )
""")

#: What :func:`imdrive.kernels.batch.worker_blocks` calls besides the loop, compiled after it.
WORKER_LATE = {"accumulate", "summarize", "_give_back"}

#: As data.compiles.COUNT_COMPILES, for a batch of one group, two drives of each estimator of
#: ``sys.argv[2]``.
COUNT_BATCH = COUNT_COMPILES.replace(
    "from imdrive.run.simulate import simulate", "from imdrive import simulate_batch"
).replace(
    'res = simulate(Scenario.read(preset, ["simulation.t_end_s=0.05"]))\nassert not res.diverged',
    'ov = ["simulation.t_end_s=0.05"]\n'
    "scs = [Scenario.read(preset, [*ov, f'control.speed_feedback=\"{e}\"']) "
    'for e in sys.argv[2].split(",") * 2]\n'
    'assert not simulate_batch(scs).metrics["diverged"].any()',
)


@pytest.mark.slow  # a cold compile of the late blocks and of the loop: 12-25 s
@pytest.mark.parametrize(
    "preset, optional, batch",
    [
        ("sensorless", set(), None),
        ("sensorless-realistic", {"bridge_period", "stator_residual"}, None),
        ("sensorless-realistic", {"bridge_period", "stator_residual"}, "mras"),
        ("sensorless", set(), "mras,afo"),  # one kernel, the union's
    ],
)
def test_the_helpers_blocks_are_what_the_loop_loads(tmp_path, preset, optional, batch):
    """A drive's cold loop, or a batch's single cold kernel, loads the late blocks the helper
    compiled for it (same types: none compiled again)."""
    env = {**os.environ, "IMDRIVE_CACHE_DIR": str(tmp_path / "cache"), prefetch.ENV: "0"}

    def py(code, *args):
        res = subprocess.run(
            [sys.executable, "-c", code, *args], env=env, capture_output=True, text=True
        )
        assert res.returncode == 0, res.stderr[-3000:]
        return res.stdout.split()

    records = tmp_path / "records.pkl"
    py(RECORDS_BATCH if batch else RECORDS, str(records), preset, *([batch] if batch else []))
    py(prefetch.HELPER, str(records))  # what start() runs, here to its end
    assert not records.exists()
    compiled = set(
        py(COUNT_BATCH if batch else COUNT_COMPILES, preset, *([batch] if batch else []))
    )
    assert "run_drive" in compiled  # the loop itself was cold
    assert not batch or "_worker" in compiled
    late = LATE | optional | (WORKER_LATE if batch else set())  # came from the helper
    assert not compiled & late, compiled & late
    # and the helper left nothing in the source tree
    src = os.path.dirname(prefetch.__file__)
    assert not [f for f in os.listdir(src) if f.endswith((".nbi", ".nbc"))]


def test_no_helper_for_a_compiled_loop_or_when_turned_off(monkeypatch):
    from imdrive.run.batch_groups import first_call as batch_call

    sc = Scenario.read("sensorless", ["simulation.t_end_s=0.01"])
    simulate(sc)  # compiled (or loaded) in this process now
    a, first = _first_call(sc)
    assert prefetch._compiled_or_cached(run_drive, first)
    # a batch of the same drives calls that loop: its types, as start_batch spells them
    P, S, *_, scratch = batch_call([(0, sc, a)], (1, a.params.est.dtype, None), 0.5)
    assert prefetch._compiled_or_cached(run_drive, prefetch.engine_call(P, S, scratch))
    assert prefetch.start_loop(run_drive, first, a.params, a.state0, new_log(1, a.log)) is None
    monkeypatch.setenv(prefetch.ENV, "0")
    assert prefetch.start_loop(None, (), None, None, None) is None  # off: nothing looked at
    assert prefetch.start([(None, ())]) is None


def test_an_unknown_specialisation_is_not_cached():
    class Stub:  # a dispatcher that has compiled nothing and whose cache knows nothing
        overloads = {}

        @staticmethod
        def typeof_pyval(v):
            from numba import typeof

            return typeof(v)

        class _cache:
            @staticmethod
            def _index_key(sig, codegen):
                return ("key", sig)

            class _cache_file:
                @staticmethod
                def _load_index():
                    return {}

        class targetctx:
            @staticmethod
            def codegen():
                return None

    assert not prefetch._compiled_or_cached(Stub, (1.0, 2))
    # numba's internals not as expected: assume cached, start nothing
    assert prefetch._compiled_or_cached(object(), (1.0,))


@pytest.mark.parametrize("estimators", [("mras", "mras"), ("mras", "afo")])
def test_the_batch_helper_compiles_each_groups_call_as_the_batch_makes_it(estimators):
    from numba import typeof

    from imdrive.kernels.batch import new_scratch
    from imdrive.kernels.estimators import union
    from imdrive.run.batch_groups import first_call, group_args, united

    # a group mixing an average and a realistic drive compiles the blocks of both; two
    # estimators, the union of all
    items = [
        (i, sc, build_arrays(sc))
        for i, sc in enumerate(
            Scenario.read(p, ["simulation.t_end_s=0.01", f'control.speed_feedback="{e}"'])
            for p, e in zip(("sensorless", "sensorless-realistic"), estimators, strict=True)
        )
    ]
    groups: dict = {}
    for it in items:
        groups.setdefault((1, it[2].params.est.dtype, it[2].params.comp.dtype), []).append(it)
    ((key, grouped),) = united(groups).items()
    first = first_call(grouped, key, 0.5)
    params, state, log, out = group_args(grouped, 7, 0.5, key[1])
    made = (params, state, log, 1, out, 1, 2, new_scratch(2, log.dtype)[1])  # batch_kernel's
    assert [typeof(a) for a in first] == [typeof(a) for a in made]
    assert "switching_bridge" in params.features.dtype.names
    assert (union.members(params.est.dtype) is not None) == (estimators[0] != estimators[1])


def _group_call(estimators, preset="sensorless"):
    """The batch worker's first call for a group of drives of ``estimators``."""
    from imdrive.run.batch_groups import first_call, united

    groups: dict = {}
    for i, e in enumerate(estimators):
        sc = Scenario.read(preset, ["simulation.t_end_s=0.01", f'control.speed_feedback="{e}"'])
        a = build_arrays(sc)
        groups.setdefault((1, a.params.est.dtype, a.params.comp.dtype), []).append((i, sc, a))
    ((key, items),) = united(groups).items()
    return first_call(items, key, 0.5)


def test_the_batch_helper_starts_from_the_last_group_or_on_the_one_kernels_blocks(monkeypatch):
    from imdrive.kernels.batch import worker_blocks
    from imdrive.kernels.prefetch import late_blocks

    seen, cached, engines = [], set(), set()

    def compiled_or_cached(d, args):
        return id(args[0]) in (engines if d is run_drive else cached)

    def jobs():  # the helper's last jobs: (function, the records they were given)
        return [(f, a[0]) for f, a in seen[-1]]

    monkeypatch.setattr(prefetch, "start", lambda jobs, check=True: seen.append(jobs))
    monkeypatch.setattr(prefetch, "_compiled_or_cached", compiled_or_cached)
    calls = [_group_call(["mras"]), _group_call(["afo"], "sensorless-realistic")]
    calls.append(_group_call(["mras", "afo", "ekf"]))  # one group: the union's records
    Pa, Pb, Pc = (c[0] for c in calls)
    prefetch.start_batch("worker", calls)
    assert jobs() == [("worker", Pc), ("worker", Pb)]
    cached.update({id(Pa), id(Pc)})  # one kernel left to compile: the helper takes its blocks
    prefetch.start_batch("worker", calls)
    assert jobs() == [(late_blocks, Pb), (worker_blocks, Pb)]
    assert seen[-1][0][1][2].shape == (1,)  # the late blocks' log: the scratch log's first row
    assert seen[-1][1][1] is calls[1]  # the worker's blocks: its own call
    engines.add(id(Pb))  # but not when its loop is compiled (a sweep after a run): no blocks
    assert prefetch.start_batch("worker", calls) is None and len(seen) == 2
    cached.add(id(Pb))
    engines.clear()
    assert prefetch.start_batch("worker", calls) is None and len(seen) == 2
    monkeypatch.setenv(prefetch.ENV, "0")
    cached.clear()
    assert prefetch.start_batch("worker", calls) is None and len(seen) == 2
