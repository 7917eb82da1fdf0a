"""Kernels compiled without the wrappers only Python needs (imdrive.kernels.jit)."""

from __future__ import annotations

import inspect

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
