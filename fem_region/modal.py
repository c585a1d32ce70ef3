"""Lowest natural modes of a FemRegion (for dynamic relaxation and vibration tests)."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

from .region import FemRegion


def lowest_modes(region: FemRegion, fixed_dofs: np.ndarray, mass: np.ndarray, k: int = 1):
    """k lowest (omega (k,) rad/s, shapes (k, n_nodes, dim)) of K phi = omega^2 M phi.

    fixed_dofs: flat DOF indices held at zero; mass: (n_nodes,) kg lumped.
    """
    free = np.setdiff1d(np.arange(region.ndof), fixed_dofs)
    K = region.K[free][:, free]
    M = sp.diags(np.repeat(mass, region.dim)[free])
    lam, vec = eigsh(K.tocsc(), k=k, M=M.tocsc(), sigma=0.0, which="LM")
    order = np.argsort(lam)
    shapes = np.zeros((k, region.ndof))
    shapes[:, free] = vec[:, order].T
    return np.sqrt(lam[order]), shapes.reshape(k, region.n_nodes, region.dim)
