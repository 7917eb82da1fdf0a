"""Helpers for the kernels' named records (numpy structured dtypes).

Every block declares its parameters and state as a numpy record dtype (complex fields for space
vectors). A drive holds each record as an array of shape ``(N,)``: ``N = 1`` for one drive, one
row per drive in a batch. Numba compiles field access to a load at a fixed offset (as fast as
a flat float array), caches functions that take records (``cache=True``), and a record taken
from an array (``state[i]``) is a view, so a block updates its state in place.

One pitfall: inside a kernel, a record taken from an array the kernel
allocated itself does not keep that array alive, and numba frees an array after its last use.
Keep using the array (``acc_arr[0].peak``, or pass ``acc_arr``) for as long as its records are
used; records of arrays passed in as arguments are safe.
"""

from __future__ import annotations

import functools

import numpy as np
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

f8 = np.float64
c16 = np.complex128
i8 = np.int64
b1 = np.bool_


def record_dtype(fields) -> np.dtype:
    """A packed record dtype from ``(name, type)`` pairs."""
    return np.dtype(list(fields))


def new_record(dtype: np.dtype, fields: dict | None = None, /, **values) -> np.ndarray:
    """A ``(1,)`` record array of ``dtype``, zeros but for the given fields (set by name):
    those of the mapping ``fields``, then the keywords.

    An unknown field name is a programming error: it raises ``KeyError`` naming it. A
    mapping is read as is, not copied into keywords: on CPython 3.11 and 3.12 a ``**`` copy
    of a dict of 20 string keys leaves about 200 bytes that only a full garbage collection
    returns (measured with tracemalloc; 19 or 21 keys, or Python 3.13, do not), and a batch of
    drives whose MRAS parameters had 20 fields grew by 400 bytes per drive.
    """
    rec = np.zeros(1, dtype=dtype)
    if not fields and not values:
        return rec
    # one assignment of the whole row: a batch builds nine records per drive, and setting
    # their 200-odd fields one by one was a tenth of its set-up (0.06 ms per drive)
    index = _field_index(dtype)
    row = list(rec[0].item())
    for part in (fields or {}, values):
        for name, val in part.items():
            pos = index.get(name)
            if pos is None:
                raise KeyError(f"{name!r} is not a field of {dtype.names}")
            row[pos] = val
    rec[0] = tuple(row)
    return rec


@functools.cache
def _field_index(dtype: np.dtype) -> dict:
    """``{field name: position}`` of a record dtype."""
    return {name: i for i, name in enumerate(dtype.names)}


def new_records(specs: dict) -> dict:
    """Several records at once: ``{name: (dtype, fields)}`` -> ``{name: new_record(dtype,
    fields)}`` (the drive's blocks, made in one call)."""
    return {name: new_record(dtype, fields) for name, (dtype, fields) in specs.items()}


def record_bytes(rec: np.ndarray) -> np.ndarray:
    """The record array's raw bytes (uint8): equal bytes mean bit-identical records."""
    return np.ascontiguousarray(rec).view(np.uint8)


@intrinsic
def copy_row(typingctx, dst, i, src, j):
    """``dst[i] = src[j]`` for two arrays of one record dtype, as one ``memcpy``.

    numba lowers a record assignment as a load and a store per byte: the seven state records
    of a drive (about 2 kB) made 8,400 lines of LLVM in the one function that copied them back
    (``kernels/batch._give_back``), optimised again in every caller, seconds of the first
    batch's compile. No bounds check, like numba's own indexing.
    """
    ok = (
        isinstance(dst, types.Array)
        and isinstance(src, types.Array)
        and isinstance(dst.dtype, types.Record)
        and dst.dtype == src.dtype
        and dst.ndim == src.ndim == 1
        and isinstance(i, types.Integer)
        and isinstance(j, types.Integer)
    )
    if not ok:
        return None

    def codegen(context, builder, sig, args):
        ary_dst = context.make_array(dst)(context, builder, args[0])
        ary_src = context.make_array(src)(context, builder, args[2])
        p_dst = cgutils.get_item_pointer(context, builder, dst, ary_dst, [args[1]], wraparound=True)
        p_src = cgutils.get_item_pointer(context, builder, src, ary_src, [args[3]], wraparound=True)
        size = context.get_constant(types.intp, dst.dtype.size)
        cgutils.raw_memcpy(builder, p_dst, p_src, size, 1)
        return context.get_dummy_value()

    return types.none(dst, i, src, j), codegen
