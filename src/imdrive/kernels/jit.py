"""numba's ``njit`` for the kernels: a block compiled without the wrappers only Python needs.

numba compiles two wrappers around every jitted function besides its native code: one that
unboxes Python arguments (the CPython wrapper) and one with the C calling convention (the
cfunc wrapper). A block that only other kernels call never uses either, yet each costs its
own lowering and machine code, and a block's compile is mostly fixed costs. With the
wrappers left out of every kernel but the Python-called entry points, 30 small record
functions compiled in 2.2 s against 4.6 s, and, paired with the commit before on these 2-core
machines (2026-12-02, benchmarks/README.md, *Kernels without numba's wrappers*), a cold
``imdrive run sensorless`` took 7.9-8.2 s against 8.8-9.1 s and the first ``bench-estimators``
after a warm run 37.0-38.2 s against 40.9-41.3 s.

A function compiled without its CPython wrapper has no native entry for Python (numba's
dispatcher would jump to a null address), so :class:`BlockDispatcher` sends a call from
Python to a twin compiled with the wrappers, cached in a file of its own. Kernels call the
block itself, so the twin only costs the blocks that tests, reports or analyses call from
Python. The entry points Python calls on every run (the engine, the batch worker) take
``entry=True`` and keep their wrappers, one compile for both callers.

Importing this module also names every compiled function by the *content* of its argument
types (:func:`_content_mangler`), for the reason given there.
"""

from __future__ import annotations

import functools
import hashlib
import types as pytypes

import numba
from numba.core import base, config, funcdesc
from numba.core.registry import CPUDispatcher

#: The options that leave the wrappers out.
NO_WRAPPERS = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True}

#: The ``jit_options`` of an ``@overload``'s implementation: numba compiles it in full to
#: type the call (its code is then inlined, or called from kernels only), so its wrappers
#: are never used either.
IMPL = dict(NO_WRAPPERS)

#: As :data:`IMPL`, cached (an implementation defined in a kernel module's source).
CACHED_IMPL = {"cache": True, **NO_WRAPPERS}


class BlockDispatcher(CPUDispatcher):
    """A kernel compiled without its wrappers; called from Python, its twin runs
    (:meth:`from_python`), with the same code, options and cache folder."""

    def __call__(self, *args, **kwargs):
        return self.from_python(*args, **kwargs)

    @functools.cached_property
    def from_python(self) -> CPUDispatcher:
        """The twin that Python calls: the same function compiled with its wrappers, named
        ``<name>__from_python`` so that its cache file is not the block's (numba's cache
        index does not tell the two compiles apart)."""
        f = self.py_func
        twin = pytypes.FunctionType(
            f.__code__, f.__globals__, f.__name__, f.__defaults__, f.__closure__
        )
        twin.__kwdefaults__ = f.__kwdefaults__
        twin.__qualname__ = f.__qualname__ + "__from_python"
        twin.__module__ = f.__module__
        twin.__doc__ = f.__doc__
        options = {k: v for k, v in self.targetoptions.items() if k not in NO_WRAPPERS}
        options.pop("nopython", None)
        options.pop("boundscheck", None)
        return numba.njit(cache=self._cache_enabled, **options)(twin)

    @property
    def _cache_enabled(self) -> bool:
        return type(self._cache).__name__ != "NullCache"


def njit(func=None, *, cache: bool = False, entry: bool = False, **options):
    """``numba.njit`` for a kernel: without the wrappers unless ``entry`` (a function Python
    calls on every run, whose twin would be a second compile of the same code).

    Parameters
    ----------
    func : function, optional
        The function (``@njit``) or None (``@njit(...)``).
    cache : bool
        Cache the compiled code (in :mod:`imdrive._cache`'s folder of the module).
    entry : bool
        Keep numba's wrappers: Python calls this function itself.
    **options
        numba's options (``inline``, ``nogil``, ``error_model``...).
    """

    def wrap(f):
        if entry or config.DISABLE_JIT:
            return numba.njit(cache=cache, **options)(f)
        targetoptions = {"nopython": True, "boundscheck": None, **options, **NO_WRAPPERS}
        disp = BlockDispatcher(py_func=f, locals={}, targetoptions=targetoptions)
        if cache:
            disp.enable_caching()
        return disp

    return wrap if func is None else wrap(func)


def _content_mangler(self, name, argtypes, *, abi_tags=(), uid=None):
    """numba's symbol name for a compiled function, tagged with a hash of its argument types
    as text (a record's text spells its fields, types and offsets).

    numba names a function by its qualified name, a per-process serial number and its
    argument types, a record type by a code each process numbers for itself. Two processes
    that compiled the same function for two different records in the same order therefore
    gave both one symbol; a third that loaded both from the cache linked every caller to the
    first one loaded, and ran it on the other's records. Reproduced in plain numba (a callee
    compiled for a one-field record and for a two-field record in two processes: the third
    returned 7.6e-322 for 10.0), and met in the clean-clone CI of 2026-11-30 (``foc_step``
    compiled for two features records, 9 tests wrong). The tag keeps the two names apart;
    ``tests/kernels/test_jit.py`` runs the three processes.
    """
    text = repr(tuple(str(t) for t in argtypes)).encode()
    tag = "c" + hashlib.blake2b(text, digest_size=8).hexdigest()
    return funcdesc.default_mangler(name, argtypes, abi_tags=(*abi_tags, tag), uid=uid)


base.BaseContext.mangler = _content_mangler
