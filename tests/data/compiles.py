"""A script that runs one short drive in a process of its own and prints the name of every
function numba compiled for it (none when every kernel came from the cache):
``python -c COUNT_COMPILES [PRESET]`` (default ``sensorless``)."""

import textwrap

COUNT_COMPILES = textwrap.dedent("""
    import sys
    from numba.core import event
    from imdrive.config.scenario import Scenario
    from imdrive.run.simulate import simulate

    compiled = []

    class Count(event.Listener):
        def on_start(self, ev):
            compiled.append(ev.data["dispatcher"].py_func.__qualname__)

        def on_end(self, ev):
            pass

    event.register("numba:compile", Count())
    preset = sys.argv[1] if len(sys.argv) > 1 else "sensorless"
    res = simulate(Scenario.read(preset, ["simulation.t_end_s=0.05"]))
    assert not res.diverged
    print(" ".join(compiled))
""")
