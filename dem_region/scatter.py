"""Bond strengths scattered by where each bond is (a quasi-brittle body's heterogeneity).

Each bond's factor 1 + s u, u uniform in [-1, 1), comes from a hash of the seed, the bond's
midpoint on the half-spacing grid and its branch vector in spacings (the two diagonals of a
cell share a midpoint; either end may come first). So one bond has one strength in every model
that holds it: a zone of
any size, a zone grown during the run (study/growth.py: the bonds it keeps and the fresh ones
alike), the all-DEM beam. Drawn in sequence instead, a wider zone would reshuffle every
strength.
"""
from __future__ import annotations

import numpy as np

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


def _mix(z: np.ndarray) -> np.ndarray:
    """splitmix64's finaliser (Steele, Lea & Flood 2014) on uint64 arrays (wrapping)."""
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


def strength_scale(x: np.ndarray, pairs: np.ndarray, d: float, seed: int, scatter: float) -> np.ndarray:
    """(nb,) each bond's strength factor 1 + scatter * u. x (n, 3) m the particles at rest,
    pairs (nb, 2) the bonds' ends, d m the lattice spacing (positions on its half grid)."""
    a, b = x[pairs[:, 0]], x[pairs[:, 1]]
    mid, branch = (a + b) / d, (b - a) / d
    if len(pairs) and np.abs(mid - np.round(mid)).max() > 1e-6:
        raise ValueError("bond midpoints off the lattice's half-spacing grid: their strengths would share keys")
    branch = np.round(branch)
    first = branch[np.arange(len(branch)), np.argmax(branch != 0, axis=1)]  # its first non-zero component
    branch *= np.where(first < 0, -1.0, 1.0)[:, None]  # either end first: one bond, one key
    keys = np.column_stack([np.round(mid), branch]).astype(np.int64).view(np.uint64)
    with np.errstate(over="ignore"):
        h = np.full(len(pairs), _mix(np.array([np.uint64(seed) * _GOLDEN]))[0])
        for k in range(keys.shape[1]):
            h = _mix(h ^ (keys[:, k] + _GOLDEN))
    u = (h >> np.uint64(11)).astype(np.float64) * 2.0**-53  # [0, 1)
    return 1.0 + scatter * (2.0 * u - 1.0)
