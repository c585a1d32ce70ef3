"""How every per-step loop of the project is compiled: numba, cached on disk, numpy's error model.

numba's default ("python") error model tests every division for a zero divisor so that it can
raise ZeroDivisionError; the test is a branch per division that also keeps LLVM from
vectorising and scheduling the loop. Under the numpy model a division by zero gives inf or nan,
as numpy's own arrays do, and the results of every other division are the same bits. Measured
on the main job's 4,413 Hoffman ply bonds (one step, serial, 2-core EPYC VM): 381 -> 242 us.
A nan that reaches the state is what the energy guard and the instability checks catch.
"""
from __future__ import annotations

from numba import njit


def kernel(fn=None, **options):
    """``@kernel`` or ``kernel(parallel=True)(fn)``: njit with the project's options."""
    options = {"cache": True, "error_model": "numpy", **options}
    return njit(**options)(fn) if fn is not None else njit(**options)
