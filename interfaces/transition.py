"""Transition interface: interface particles hosted by FEM elements, and the maps across it.

W (k, n_nodes) holds the shape-function weights N_a(xi_p) of each interface particle p in
its host element. The displacement / velocity map FEM -> particles is x_p = W x, and the
force map particles -> FEM is its transpose f = W^T F, so the interface does no net work
and conserves momentum; particle masses are shared to the nodes by the same weights.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import skfem

from fem_region.region import FemRegion

from .kernels import csr_times


class InterfaceError(ValueError):
    """An interface particle without a host element, or weights that do not sum to one."""


@dataclass
class TransitionInterface:
    """ids: (k,) interface particle indices; W: (k, n_nodes) sparse weights; dim: FEM dimension."""

    ids: np.ndarray
    W: sp.csr_matrix
    dim: int

    def __post_init__(self):
        self._WT = self.W.T.tocsr()  # the transpose map, built once (scipy makes a new one per .T)
        # the maps' results, rewritten in place at every call (the coupled step's buffers)
        self._at_particles = np.zeros((len(self.ids), 3))
        self._at_nodes = np.zeros((self.W.shape[1], self.dim))

    @classmethod
    def build(cls, region: FemRegion, x: np.ndarray, ids: np.ndarray, tol: float = 1e-9) -> "TransitionInterface":
        """Host particles ``ids`` at positions x (n, 3) m in the elements of ``region``."""
        ids = np.asarray(ids, int)
        if ids.size == 0:
            raise InterfaceError("interface band has no particles")
        pts = x[ids, : region.dim].T
        basis = skfem.Basis(region.mesh, region.etype.element_cls())
        W = cls._host(basis, region, pts, ids, tol).tocsr()
        W.eliminate_zeros()
        rows = np.asarray(W.sum(axis=1)).ravel()
        bad = np.flatnonzero(np.abs(rows - 1.0) > tol)
        if bad.size:
            p = ids[bad[0]]
            raise InterfaceError(f"interface particle {p} at {x[p]} has weights summing to {rows[bad[0]]:.6g}, not 1 "
                                 "(no FEM element hosts it)")
        return cls(ids, W, region.dim)

    @classmethod
    def _host(cls, basis, region: FemRegion, pts: np.ndarray, ids: np.ndarray, tol: float) -> sp.spmatrix:
        """Weights (k, n_nodes) of points pts (dim, k): all at once; when the element finder
        rejects some point (on the mesh boundary by round-off), each half again, so that only
        the rejected points are hosted one by one (_host_one)."""
        try:
            return basis.probes(pts)
        except ValueError:
            if pts.shape[1] == 1:
                return cls._host_one(basis, region, pts[:, 0], ids[0], tol)
        h = pts.shape[1] // 2
        return sp.vstack([cls._host(basis, region, pts[:, :h], ids[:h], tol),
                          cls._host(basis, region, pts[:, h:], ids[h:], tol)])

    @staticmethod
    def _host_one(basis, region: FemRegion, pt: np.ndarray, pid: int, tol: float) -> sp.csr_matrix:
        """Weights of one point; a point on the mesh boundary that the element finder rejects by
        round-off is moved 1e-9 element sizes towards the centre of one of the nearest elements
        (the nearest centre may lie across a hole whose edge the point is on: up to eight are
        tried, nearest first)."""
        try:
            return basis.probes(pt[:, None])
        except ValueError:
            pass
        centres = region.X[region.mesh.t.T].mean(axis=1)
        for e in np.argsort(np.sum((centres - pt) ** 2, axis=1))[:8]:
            size = np.ptp(region.X[region.mesh.t[:, e]], axis=0).max()
            step = centres[e] - pt
            dist = np.linalg.norm(step)
            if dist > 0:
                nudged = pt + step / dist * min(1e-9 * size, dist)
                try:
                    return basis.probes(nudged[:, None])
                except ValueError:
                    pass
        raise InterfaceError(f"interface particle {pid} at {pt} lies outside the FEM mesh; allowed: particles "
                             "inside or on the boundary of the FEM region")

    def to_particles(self, nodal: np.ndarray) -> np.ndarray:
        """nodal (n_nodes, dim) -> (k, 3) values at the interface particles (z = 0 in 2D); the
        result is this interface's buffer, overwritten by the next call."""
        W = self.W
        csr_times(W.indptr, W.indices, W.data, np.ascontiguousarray(nodal, float), self._at_particles[:, : self.dim])
        return self._at_particles

    def to_nodes(self, F: np.ndarray) -> np.ndarray:
        """F (k, 3) N on the particles -> (n_nodes, dim) N on the nodes (transpose map); the
        result is this interface's buffer, overwritten by the next call."""
        WT = self._WT
        csr_times(WT.indptr, WT.indices, WT.data, np.ascontiguousarray(F, float), self._at_nodes)
        return self._at_nodes

    def share_mass(self, m: np.ndarray) -> np.ndarray:
        """m (k,) kg of the interface particles -> (n_nodes,) kg added to the nodes."""
        return self._WT @ m
