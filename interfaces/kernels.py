"""The interface maps' products compiled into given buffers (no allocation per step).

scipy's sparse product allocates its result and spends ~8 us in Python per call; the
transition interface applies W and W^T at every DEM step. Same sums in the same order as
scipy's csr_matvecs (each row's stored entries in turn, from zero), so the digits agree.
"""
from __future__ import annotations

from physics.compiled import kernel


@kernel
def csr_times(indptr, indices, data, X, out):
    """out (n_rows, c) = A X for A in CSR form (indptr, indices, data) and X (n_cols, >= c):
    only X's first c columns are read (the FEM's dim of a particle's (k, 3) array)."""
    c = out.shape[1]
    for i in range(out.shape[0]):
        for k in range(c):
            acc = 0.0
            for jj in range(indptr[i], indptr[i + 1]):
                acc += data[jj] * X[indices[jj], k]
            out[i, k] = acc
