"""Kernels compiled without the wrappers only Python needs (imdrive.kernels.jit)."""

from __future__ import annotations

import inspect
import os
import subprocess
import sys

import numba
import numpy as np
import pytest

from imdrive.kernels import ifoc
from imdrive.kernels.jit import BlockDispatcher, njit


# not cached: the tests read the LLVM of a fresh compile (code loaded from a warm cache has
# none, and a caller loaded from it never compiles its block)
@njit
def _scaled(x, k=2.0):
    return k * x


@njit
def _caller(x):
    return _scaled(x) + 1.0


def _llvm_of(disp, sig) -> str:
    return disp.overloads[sig].library.get_llvm_str()


def test_a_block_called_by_a_kernel_has_no_python_wrapper():
    assert _caller(1.5) == 4.0
    sig = _scaled.signatures[0]
    wrapper = _scaled.overloads[sig].fndesc.llvm_cpython_wrapper_name
    assert wrapper not in _llvm_of(_scaled, sig)  # left out: no lowering, no machine code
    # the caller's own module still carries its wrapper: Python calls it through its twin
    assert isinstance(_caller, BlockDispatcher)


def test_a_block_called_from_python_runs_its_twin_with_the_same_result():
    x = np.linspace(-1.0, 1.0, 5)
    assert _scaled(0.25) == _scaled.py_func(0.25)
    assert _scaled(0.25, k=3.0) == 0.75  # keyword arguments and defaults pass through
    np.testing.assert_array_equal(_scaled(x), 2.0 * x)
    twin = _scaled.from_python
    assert not isinstance(twin, BlockDispatcher)
    sig = twin.signatures[0]
    assert twin.overloads[sig].fndesc.llvm_cpython_wrapper_name in _llvm_of(twin, sig)
    assert twin.py_func.__code__ is _scaled.py_func.__code__


def test_the_twin_is_cached_in_a_file_of_its_own():
    # numba's cache index does not tell a compile with wrappers from one without: sharing a
    # file, a process could load the wrapper-less code for a call from Python and crash
    block, twin = ifoc.foc_step, ifoc.foc_step.from_python
    assert block._cache._cache_path == twin._cache._cache_path  # the module's folder
    assert block._cache._cache_file._index_name != twin._cache._cache_file._index_name


def _kernels():
    import importlib
    import pkgutil

    import imdrive.kernels as K

    for info in pkgutil.walk_packages(K.__path__, K.__name__ + "."):
        mod = importlib.import_module(info.name)
        for name, obj in vars(mod).items():
            if (
                isinstance(obj, numba.core.dispatcher.Dispatcher)
                and obj.py_func.__module__ == info.name
            ):
                yield f"{info.name}.{name}", obj


def test_every_kernel_is_a_block_unless_declared_an_entry():
    # a kernel decorated with numba's own njit would compile its wrappers again: each
    # kernel is a block, or says ``entry=True`` (Python calls it on every run)
    kernels = dict(_kernels())
    assert "imdrive.kernels.engine.run_drive" in kernels  # the walk is not vacuous
    stray = [
        name
        for name, d in kernels.items()
        if not isinstance(d, BlockDispatcher)
        and "entry=True" not in "".join(inspect.getsourcelines(d.py_func)[0][:3])
    ]
    assert not stray, f"compiled with numba's wrappers but not declared entries: {stray}"
    blocks = sum(isinstance(d, BlockDispatcher) for d in kernels.values())
    assert blocks > 200


@pytest.mark.parametrize("entry", [True, False])
def test_options_reach_numba(entry):
    @njit(entry=entry, error_model="numpy")
    def ratio(a, b):
        return a / b

    assert np.isinf(ratio(1.0, 0.0))  # numpy's error model: no ZeroDivisionError
    assert isinstance(ratio, BlockDispatcher) is (not entry)


_TWO_RECORDS = """
import sys
import numpy as np
import imdrive.kernels.jit  # noqa: F401  (the package's symbol names)
from numba import njit

@njit(cache=True, _dbg_optnone=True)  # optnone: never inlined into its caller
def inner(r):
    return r.a * 2.0

@njit(cache=True)
def outer(arr):
    return inner(arr[0])

A = np.ones(1, dtype=[("a", np.float64)])
A["a"] = 3.0
B = np.ones(1, dtype=[("b", np.int64), ("a", np.float64)])
B["a"], B["b"] = 5.0, 77
which = sys.argv[1]
for x in {"A": [A], "B": [B], "AB": [A, B], "BA": [B, A]}[which]:
    print(outer(x))
"""


def test_two_processes_compiling_one_function_for_two_records_give_two_symbols(tmp_path):
    # each process numbers record types for itself: the same function compiled for another
    # record in another process, in the same order, had the same symbol name, and a process
    # that loaded both ran the first for both (7.6e-322 for 10.0 in plain numba)
    (tmp_path / "two_records.py").write_text(_TWO_RECORDS)
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}

    def run(which):
        out = subprocess.run(
            [sys.executable, "two_records.py", which],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
        return [float(v) for v in out.stdout.split()]

    assert run("A") == [6.0] and run("B") == [10.0]  # two processes, one compile each
    assert run("AB") == [6.0, 10.0]  # a third loads both from the cache
    assert run("BA") == [10.0, 6.0]
