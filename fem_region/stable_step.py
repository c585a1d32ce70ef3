"""The central-difference stable step of the assembled model: 2 / omega_max.

omega_max^2 is the largest eigenvalue of M^-1/2 K M^-1/2 (lumped masses M, small-strain
stiffness K of the elements plus the springs models add between nodes: cohesive pairs,
node-to-face bonds). The element-by-element bound (Irons: omega_max is at most the largest
element's own) and a sum of bounds for the springs (omega^2 <= omega_el^2 + 4 k / m) are safe
but each gives a margin away: on the seed beam's cohesive far field the two together gave a
step 1.45 x shorter than the assembled one. Abaqus/Explicit likewise starts from the element
bound and moves to a global estimate of the whole model's highest frequency
(abaqus-docs.mit.edu/2017/English/SIMACAEGSARefMap/simagsa-c-nlnautomaticexp.htm).

The eigenvalue is found by Lanczos (scipy's ARPACK) from a fixed start vector, so a run's step
is the same at every start and resume; small models by a dense solve. A Ritz value never
exceeds the eigenvalue it converges to: the clock's safety factor (clock.safety) carries the
convergence tolerance (1e-10 relative), far below it.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

DENSE_BELOW = 400  # DOFs: a dense eigvalsh is faster than ARPACK's set-up below this


def spring_stiffness(n_nodes: int, dim: int, nodes: np.ndarray, coef: np.ndarray, k: np.ndarray) -> sp.csr_matrix:
    """(n_nodes dim, n_nodes dim) N/m of springs k (nb,) N/m, each acting alike along every axis
    on the combination sum_a coef[b, a] u[nodes[b, a]] of its nodes (nb, q): a node pair is
    nodes (i, j), coef (1, -1); a node-to-face bond its slave and face nodes, (1, -w_1, ...)."""
    nodes, coef = np.asarray(nodes), np.asarray(coef, float)
    nb, q = nodes.shape
    vals = (np.asarray(k, float)[:, None, None] * coef[:, :, None] * coef[:, None, :])  # (nb, q, q)
    rows = np.broadcast_to(nodes[:, :, None], (nb, q, q)).ravel() * dim
    cols = np.broadcast_to(nodes[:, None, :], (nb, q, q)).ravel() * dim
    axes = np.arange(dim)  # the same springs along each axis
    return sp.csr_matrix((np.tile(vals.ravel(), dim), (np.concatenate(rows + axes[:, None]),
                                                        np.concatenate(cols + axes[:, None]))),
                         shape=(n_nodes * dim, n_nodes * dim))


def pair_springs(n_nodes: int, dim: int, pairs: np.ndarray, k: np.ndarray) -> sp.csr_matrix:
    """spring_stiffness of springs k (nb,) N/m on node pairs (nb, 2)."""
    return spring_stiffness(n_nodes, dim, pairs, np.tile([1.0, -1.0], (len(pairs), 1)), k)


def largest_frequency_squared(K: sp.spmatrix, m: np.ndarray, dim: int) -> float:
    """omega_max^2 (1/s^2) of K (n dim, n dim) N/m with lumped masses m (n,) kg (massless
    DOFs, which carry no inertia, are left out)."""
    md = np.repeat(np.asarray(m, float), dim)
    keep = np.flatnonzero(md > 0)
    s = 1.0 / np.sqrt(md[keep])
    A = sp.csr_matrix(K)[keep][:, keep]
    A = sp.diags(s) @ A @ sp.diags(s)
    A = 0.5 * (A + A.T)  # symmetric to round-off, as ARPACK's symmetric driver assumes
    if A.shape[0] == 0:
        return 0.0
    if A.shape[0] < DENSE_BELOW:
        return float(np.linalg.eigvalsh(A.toarray())[-1])
    v0 = np.random.default_rng(20261207).standard_normal(A.shape[0])  # fixed: the same step every run
    return float(sla.eigsh(A, k=1, which="LA", tol=1e-10, v0=v0, return_eigenvectors=False)[0])


def assembled_critical_dt(K: sp.spmatrix, m: np.ndarray, dim: int) -> float:
    """2 / omega_max (s) of K (n dim, n dim) N/m and lumped masses m (n,) kg; inf if nothing
    is stiff."""
    lam = largest_frequency_squared(K, m, dim)
    return float(2.0 / np.sqrt(lam)) if lam > 0 else np.inf
