"""A pressure history on a disc of a 3D body's top face ([loads.*] kind = "pressure"): the
whole force against time (a table or a CSV file) spread uniformly over a disc of radius r
about the top face's centre, in the quarter model a quarter of it. The FEM's top faces take
their consistent nodal shares (disc.face_shares: the integral of each node's shape function
over the part of its faces inside the disc); each top particle takes the part of its d x d
footprint under the disc, inside the quarter, the body and the zone's selected cells. The two
sum to the quarter disc wherever the zone's edge cuts it.
"""
from __future__ import annotations

import numpy as np

from dem_region.particle_load import ParticleLoad
from fem_region.explicit import NodalLoad

from .disc import face_shares


def fem_pressure(p: dict, loads: list[str], region, H: float, curve) -> list[NodalLoad]:
    """The FEM's part of the study's pressure load (none without one, or when no FEM face is
    under the disc): downward nodal forces on the top faces at z = H, per N of curve(t)."""
    if not loads:
        return []
    r = p[f"loads.{loads[0]}.radius"]
    share = face_shares(region, H, r)  # m^2
    nodes = np.flatnonzero(share > 0)
    return [NodalLoad(3 * nodes + 2, -share[nodes] / (np.pi * r**2), curve)] if nodes.size else []


def particle_pressure(p: dict, name: str, lattice, cells: np.ndarray | None, half_sides, curve) -> ParticleLoad:
    """The particles' part of the pressure load [loads.name]: on the lattice's top row, each the
    part of its footprint under the disc (cells: ply_block.carve's padded mask of the zone;
    None: the whole body, of half sides (x, y) m)."""
    r = p[f"loads.{name}.radius"]
    k = lattice.index[:, 2]
    top = np.flatnonzero(k == k.max())
    share = footprint_shares(lattice.x[top, :2], lattice.d, r, cells, half_sides)
    on = share > 0
    return ParticleLoad(top[on], np.outer(-share[on] / (np.pi * r**2), [0.0, 0.0, 1.0]), curve)


def footprint_shares(xy: np.ndarray, d: float, r: float, cells: np.ndarray | None, half_sides) -> np.ndarray:
    """(k,) m^2: the part of each particle's d x d footprint about xy (k, 2) inside the disc of
    radius r about the origin, the quarter x, y >= 0, the body's half sides and the selected
    ``cells``, by midpoint sums on 40 x 40 sub-cells."""
    n = 40
    g = (np.arange(n) + 0.5) / n - 0.5
    sx, sy = (a.ravel() * d for a in np.meshgrid(g, g, indexing="ij"))
    X, Y = xy[:, :1] + sx, xy[:, 1:2] + sy  # (k, n^2)
    ok = (X >= 0) & (Y >= 0) & (X <= half_sides[0]) & (Y <= half_sides[1]) & (np.hypot(X, Y) <= r)
    if cells is not None:
        a = np.clip(np.floor(X / d).astype(int) + 1, 0, cells.shape[0] - 1)
        b = np.clip(np.floor(Y / d).astype(int) + 1, 0, cells.shape[1] - 1)
        ok &= cells[a, b]
    return ok.sum(axis=1) * (d / n) ** 2
