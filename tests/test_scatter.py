"""Bond strengths scattered by where each bond is (dem_region/scatter.py): uniform in 1 +- s
over a lattice's bonds whatever the seed, independent between seeds and between the two
diagonals of a cell, and one bond's factor the same in a lattice of any size."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from dem_region.scatter import strength_scale


def _lattice(n: int, m: int, d: float):
    """A square lattice's particles (n x m, spacing d) and its bonds: along x, along y and both diagonals."""
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    x = np.column_stack([i.ravel() * d, j.ravel() * d + 0.5 * d, np.zeros(i.size)])
    k = lambda a, b: a * m + b
    pairs = []
    for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
        a, b = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
        ok = (a + di < n) & (b + dj >= 0) & (b + dj < m)
        pairs.append(np.column_stack([k(a[ok], b[ok]), k(a[ok] + di, b[ok] + dj)]))
    return x, np.vstack(pairs)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), s=st.floats(0.01, 0.5), d=st.floats(1e-4, 1e-2))
def test_the_scatter_is_uniform_and_keyed_by_place(seed, s, d):
    x, pairs = _lattice(60, 20, d)
    f = strength_scale(x, pairs, d, seed, s)
    u = (f - 1) / s
    assert u.min() >= -1 and u.max() < 1
    n = len(u)
    # uniform on [-1, 1): mean 0 (sd 1 / sqrt(3 n)), a quarter in each quarter of the interval (binomial sd)
    assert abs(u.mean()) < 5 / np.sqrt(3 * n)
    counts = np.histogram(u, bins=4, range=(-1, 1))[0]
    assert np.all(np.abs(counts - n / 4) < 5 * np.sqrt(n * 3 / 16))
    # another seed: uncorrelated; the two diagonals of a cell (one midpoint): not the same
    other = (strength_scale(x, pairs, d, seed + 1, s) - 1) / s
    assert abs(np.corrcoef(u, other)[0, 1]) < 5 / np.sqrt(n)
    mid = np.round((x[pairs[:, 0]] + x[pairs[:, 1]]) / d).astype(int)
    _, count = np.unique(mid, axis=0, return_counts=True)
    assert np.all(count <= 2) and len(np.unique(f)) == n
    # either end first: the same bond, the same factor
    assert np.array_equal(strength_scale(x, pairs[:, ::-1], d, seed, s), f)
    # a smaller lattice's bonds (the first 30 columns, offset in the big one's order) keep their factors
    xs, ps = _lattice(30, 20, d)
    fs = strength_scale(xs, ps, d, seed, s)
    big = {tuple(np.round(np.concatenate([x[a], x[b]]) / d, 6)): v for (a, b), v in zip(pairs, f)}
    assert all(big[tuple(np.round(np.concatenate([xs[a], xs[b]]) / d, 6))] == v for (a, b), v in zip(ps, fs))
