"""How every per-step loop of the project is compiled: numba, cached on disk, numpy's error model.

numba's default ("python") error model tests every division for a zero divisor so that it can
raise ZeroDivisionError; the test is a branch per division that also keeps LLVM from
vectorising and scheduling the loop. Under the numpy model a division by zero gives inf or nan,
as numpy's own arrays do, and the results of every other division are the same bits. Measured
on the main job's 4,413 Hoffman ply bonds (one step, serial, 2-core EPYC VM): 381 -> 242 us.
A nan that reaches the state is what the energy guard and the instability checks catch.
"""
from __future__ import annotations

import types

from numba import njit

from . import compile_clock  # noqa: F401 (counts this process's compilations from here on)


def kernel(fn=None, **options):
    """``@kernel`` or ``kernel(parallel=True)(fn)``: njit with the project's options."""
    options = {"cache": True, "error_model": "numpy", **options}
    build = lambda f: njit(**options)(_cached_as(f, "parallel" if options.get("parallel") else "serial"))
    return build(fn) if fn is not None else build


def _cached_as(fn, build: str):
    """``fn`` under a name of its own in numba's disk cache. The cache's key is the function's
    name, bytecode and signature, not its compile options: a serial and a parallel build of
    one function loaded each other's machine code, and a YADE process (whose OpenMP runtime
    numba's must not share) that called the serial build ran the parallel one and crashed."""
    twin = types.FunctionType(fn.__code__, fn.__globals__, fn.__name__, fn.__defaults__, fn.__closure__)
    twin.__kwdefaults__, twin.__doc__, twin.__module__ = fn.__kwdefaults__, fn.__doc__, fn.__module__
    twin.__qualname__ = f"{fn.__qualname__}.{build}"
    return twin
