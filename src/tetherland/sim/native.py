"""MuJoCo's step functions and the plant's arrays, reached from compiled kernels.

A compiled kernel called from Python pays numba's type dispatch and the unboxing of its
arguments on each call (about 0.2 us, and 0.04 us more per array; a ctypes function
passed as an argument about 1 us), and the MuJoCo Python bindings their own call overhead
around ``mj_step1`` and ``mj_step2``. The plant's physics
step (:func:`~tetherland.sim.step_kernel.physics_step`) avoids both: it receives one
int64 *address table* made once per plant, with the addresses of the MuJoCo functions
(:func:`step_functions`), of ``mjModel`` and ``mjData`` (``MjModel._address``) and of the
arrays it reads and writes, and views them inside the kernel (:func:`f64_at`,
:func:`i32_at`, :func:`call_model_data`). The addresses are runtime values, so numba's
disk cache stays valid across processes.

The arrays behind a table must outlive it and never be reallocated (views into ``MjData``
are stable for the life of the data; the plant keeps its own arrays referenced). MuJoCo's
fatal errors (``mju_error``, e.g. an arena too small for the contacts) cannot be caught
inside a compiled frame: only plants whose arena cannot overflow use the table (the plant
decides, :attr:`~tetherland.sim.plant.Plant.compiled_step`).

Where the MuJoCo library cannot be located next to its Python package, or reports another
version than the bindings, :func:`step_functions` returns None and the plant steps through
the Python bindings (the same bits, slower).
"""

from __future__ import annotations

import ctypes
import functools
from pathlib import Path

import mujoco
import numpy as np
from llvmlite import ir
from numba import carray, njit, types
from numba.extending import intrinsic

__all__ = ["address", "call_model_data", "f64_at", "f64_matrix_at", "i32_at", "step_functions"]

_LIBRARY_PATTERNS = ("libmujoco.so*", "libmujoco*.dylib", "mujoco*.dll")


@functools.cache
def step_functions() -> tuple[int, int] | None:
    """Addresses of ``mj_step1`` and ``mj_step2`` of the MuJoCo library the Python package
    loaded (None if it cannot be found: the caller falls back to the bindings)."""
    root = Path(mujoco.__file__).parent
    for pattern in _LIBRARY_PATTERNS:
        for path in sorted(root.glob(pattern)):
            try:
                lib = ctypes.CDLL(str(path))  # the same loaded library: dlopen counts it once
                lib.mj_version.restype = ctypes.c_int
                if lib.mj_version() != mujoco.mj_version():  # another build: not ours
                    continue
                return tuple(  # type: ignore[return-value]
                    int(ctypes.cast(getattr(lib, name), ctypes.c_void_p).value or 0)
                    for name in ("mj_step1", "mj_step2")
                )
            except (OSError, AttributeError):
                continue
    return None


def address(array: np.ndarray, dtype: type = np.float64) -> int:
    """Address of the first element of ``array`` (C-contiguous, or a single element),
    checked to hold ``dtype``."""
    if array.dtype != dtype:
        raise TypeError(f"expected a {np.dtype(dtype).name} array, got {array.dtype}")
    if not (array.flags.c_contiguous or array.size <= 1):
        raise ValueError("the array must be C-contiguous")
    return int(array.ctypes.data)


def _pointer_cast(item: types.Type):  # type: ignore[no-untyped-def]
    """An intrinsic: an int64 address as a typed pointer to ``item`` (for ``carray``)."""

    @intrinsic
    def cast(typingctx, addr):  # type: ignore[no-untyped-def]
        sig = types.CPointer(item)(types.int64)

        def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
            return builder.inttoptr(args[0], context.get_value_type(types.CPointer(item)))

        return sig, codegen

    return cast


_f64_pointer = _pointer_cast(types.float64)
_i32_pointer = _pointer_cast(types.int32)


@intrinsic
def call_model_data(typingctx, fn, model, data):  # type: ignore[no-untyped-def]
    """``fn(model, data)`` for the C function ``void fn(const mjModel*, mjData*)`` at the
    address ``fn`` (int64 addresses, in a compiled kernel)."""
    sig = types.void(types.int64, types.int64, types.int64)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        void_p = ir.IntType(8).as_pointer()
        fn_type = ir.FunctionType(ir.VoidType(), [void_p, void_p])
        f = builder.inttoptr(args[0], fn_type.as_pointer())
        builder.call(f, [builder.inttoptr(args[1], void_p), builder.inttoptr(args[2], void_p)])
        return context.get_dummy_value()

    return sig, codegen


@njit(cache=True, inline="always")
def f64_at(addr: int, n: int) -> np.ndarray:
    """The ``n`` float64 values at ``addr`` as an array view (in a compiled kernel)."""
    return carray(_f64_pointer(addr), (n,))


@njit(cache=True, inline="always")
def i32_at(addr: int, n: int) -> np.ndarray:
    """The ``n`` int32 values at ``addr`` as an array view (in a compiled kernel)."""
    return carray(_i32_pointer(addr), (n,))


@njit(cache=True, inline="always")
def f64_matrix_at(addr: int, rows: int, cols: int) -> np.ndarray:
    """The (rows, cols) C-ordered float64 values at ``addr`` as an array view."""
    return carray(_f64_pointer(addr), (rows, cols))
