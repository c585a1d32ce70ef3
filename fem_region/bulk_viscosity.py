"""Bulk viscosity for shock-type loading (von Neumann-Richtmyer / LS-DYNA form).

Under compression (volumetric strain rate d < 0) each element carries a pressure
q = rho l (C0 l d^2 - C1 c d), which smears shocks over a few elements and damps the
ringing behind them; in tension q = 0. Defaults C0 = 1.5, C1 = 0.06 are LS-DYNA's.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kernels import add_bulk_viscosity_force


@dataclass
class BulkViscosity:
    """b: (nel, n_loc, dim) 1/m centroid gradients; vol: (nel,) m^3; length: (nel,) m;
    c: (nel,) m/s dilatational wave speed; rho: (nel,) kg/m^3; conn: (nel, n_loc) nodes."""

    b: np.ndarray
    vol: np.ndarray
    length: np.ndarray
    c: np.ndarray
    rho: np.ndarray
    conn: np.ndarray
    C0: float = 1.5
    C1: float = 0.06

    @classmethod
    def of(cls, region, C0: float = 1.5, C1: float = 0.06) -> "BulkViscosity":
        from .region import _quadrature

        q = _quadrature(region.mesh, region.etype, region.etype.one_point_rule(), region.thickness, [])
        vol = q.dx[:, 0]
        length = (vol / region.thickness) ** (1.0 / region.dim) if region.dim == 2 else vol ** (1 / 3)
        cmax = np.einsum("eii->ei", region.D)[:, : region.dim].max(axis=1)
        return cls(np.ascontiguousarray(q.dN[:, 0]), vol, length, np.sqrt(cmax / region.rho), region.rho,
                   np.ascontiguousarray(region.mesh.t.T), C0, C1)

    def pressure(self, v: np.ndarray) -> np.ndarray:
        """(nel,) Pa for nodal velocities v (n_nodes, dim)."""
        d = np.einsum("eai,eai->e", self.b, v[self.conn])
        d = np.minimum(d, 0.0)
        return self.rho * self.length * (self.C0 * self.length * d * d - self.C1 * self.c * d)

    def add_force(self, v: np.ndarray, out: np.ndarray) -> None:
        """out (n_nodes, dim) N += the resisting nodal force at nodal velocities v (added like a
        damping force, so it is subtracted from the kick), in place."""
        add_bulk_viscosity_force(self.b, self.vol, self.length, self.c, self.rho, self.conn, self.C0, self.C1,
                                 np.ascontiguousarray(v, float), out)

    def force(self, v: np.ndarray) -> np.ndarray:
        """(n_nodes, dim) N, the resisting nodal force (to be subtracted like a damping force)."""
        out = np.zeros_like(v)
        self.add_force(v, out)
        return out
