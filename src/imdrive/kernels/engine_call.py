"""The engine called through its address: the stability map runs the
:func:`~imdrive.kernels.engine.run_drive` that ``imdrive run`` compiled, without linking its
code into its own kernels.

numba compiles a call from one jitted function to another by linking the callee's LLVM module
into the caller's and optimising the whole again (``CPUCodeLibrary.finalize``: every linked
library goes through the module pass manager and the machine-code emitter once more), in
every entry point that reaches it. The map has three (the workers of ``solve_points``,
``propagate`` and ``step_check``), each paying the engine's optimisation again on its first
use, cached by ``run`` or not.

Here the caller receives the engine's native entry as an integer (:func:`engine_address`,
which loads or compiles ``run_drive`` for the exact argument types) and calls it with
numba's own calling convention (:func:`call_engine`), as numba calls a linked function: the
same code runs, and the caller's module holds only its own. The address is a run-time
argument, never a constant, so the callers' cached machine code stays valid in every
process. Measured 2026-11-30 (``benchmarks/bench_compile.py --warm-first "run sensorless
-q" --cmd "stability sensorless -q"``): the first map after a warm run compiled 9.7 s
instead of 12.0 s, and a warm map ran as fast (wall 0.97 of linked, ``farm-bench``, 5 runs).

The batch keeps the engine linked (:mod:`imdrive.kernels.batch`): re-optimised with its
callers, it ran a batch of one-second drives about 1.4 times as fast.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from imdrive.kernels.engine import run_drive
from imdrive.kernels.recording import RECORDING

#: The ``rec`` argument of a run that records nothing (``simulate()``'s type).
NO_RECORDING = np.zeros(0, dtype=RECORDING)


def engine_signature(P, S, log) -> tuple:
    """The numba argument types of ``run_drive(P, S, i, n_steps, log, log_every, k0, final,
    rec)`` as ``simulate()`` calls it (integers int64, ``final`` a bool, ``rec``
    :data:`NO_RECORDING`), for parameters ``P``, state ``S`` and log ``log`` of these types."""
    i8 = types.int64
    typeof = numba.typeof
    return (typeof(P), typeof(S), i8, i8, typeof(log), i8, i8, types.boolean, typeof(NO_RECORDING))


def _compiled(argtypes: tuple):
    """``run_drive``'s compile result for ``argtypes``, loaded from the cache or compiled."""
    cres = run_drive.overloads.get(argtypes)
    if cres is None:
        run_drive.compile(argtypes)
        cres = run_drive.overloads[argtypes]
    return cres


def engine_address(P, S, log) -> int:
    """The address of ``run_drive``'s native entry for :func:`engine_signature` ``(P, S,
    log)``, to hand to a kernel that runs it through :func:`call_engine`.

    The first call in a process loads (or compiles) the engine as ``imdrive run`` does; the
    address is valid for the life of the process.
    """
    cres = _compiled(engine_signature(P, S, log))
    address = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
    if not address:
        raise RuntimeError("run_drive's native entry is missing from its compiled library")
    return address


@intrinsic
def call_engine(typingctx, engine, P, S, i, n_steps, log, log_every, k0, final, rec):
    """``run_drive(P, S, i, n_steps, log, log_every, k0, final, rec)`` through the address
    ``engine`` (:func:`engine_address` for the same argument types): returns ``(status,
    k)``, as ``run_drive`` does.

    The arguments must have :func:`engine_signature`'s types (int64 integers, a bool
    ``final``; a constant is typed as its run-time type): typing resolves ``run_drive`` for
    them, and an address of the engine compiled for other types would run the wrong code.
    """
    argtypes = tuple(types.unliteral(t) for t in (P, S, i, n_steps, log, log_every, k0, final, rec))
    restype = _compiled(argtypes).signature.return_type

    def codegen(context, builder, sig, args):
        fnty = context.call_conv.get_function_type(restype, argtypes)
        fn = builder.inttoptr(args[0], fnty.as_pointer())
        status, out = context.call_conv.call_function(builder, fn, restype, argtypes, args[1:])
        with cgutils.if_unlikely(builder, status.is_error):
            context.call_conv.return_status_propagate(builder, status)
        return out

    return restype(types.intp, *argtypes), codegen
