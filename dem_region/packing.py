"""Particle packings that fill a box, with bonds between touching neighbours.

Regular packings: hexagonal (2D, one quasi-2D layer of spheres in the x-y plane), simple
cubic and hexagonal close packed (3D). Random dense packing: random sequential placement
followed by bonding of neighbours within a tolerance. All lengths in m.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .scene import check_fits


def hexagonal_2d(lo, hi, radius: float) -> np.ndarray:
    """(n, 3) centres of a triangular lattice (spacing 2r) whose spheres lie inside the
    rectangle lo..hi (x, y); rows along x, z = 0. Includes spheres centred on the box edges
    where a row fits exactly."""
    (x0, y0), (x1, y1) = lo, hi
    d = 2.0 * radius
    dy = np.sqrt(3.0) * radius
    eps = 1e-9 * d
    pts = []
    for j in range(int(np.floor((y1 - y0) / dy + 1e-9)) + 1):
        y = y0 + j * dy
        off = 0.5 * d if j % 2 else 0.0
        xs = np.arange(x0 + off, x1 + eps, d)
        pts += [(x, y, 0.0) for x in xs]
    return np.array(pts)


def square_2d(lo, hi, radius: float) -> np.ndarray:
    """(n, 3) centres of a square lattice (spacing 2r) in the x-y plane from lo to hi inclusive."""
    pts = simple_cubic((lo[0], lo[1], 0.0), (hi[0], hi[1], 0.0), radius)
    return pts


def square_bonds(x: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Bonds of a square lattice: (pairs (nb, 2), family (nb,)), family 0 = axial neighbours
    at 2r, family 1 = diagonal neighbours at 2 sqrt(2) r (they carry the shear stiffness)."""
    tree = cKDTree(x)
    pairs = np.array(sorted(tree.query_pairs(2 * np.sqrt(2) * radius * (1 + 1e-6))), dtype=int).reshape(-1, 2)
    dist = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
    family = (dist > 2 * radius * (1 + 1e-6)).astype(int)
    return pairs, family


def simple_cubic(lo, hi, radius: float) -> np.ndarray:
    """(n, 3) centres of a simple cubic lattice (spacing 2r) from lo to hi inclusive."""
    counts = [np.floor((b - a) / (2 * radius) + 1e-9) + 1 for a, b in zip(lo, hi)]
    check_fits(np.prod(counts), f"particle radius {radius:g} m over {np.subtract(hi, lo).tolist()} m")
    axes = [np.arange(a, b + 1e-9 * radius, 2 * radius) for a, b in zip(lo, hi)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


def hcp(lo, hi, radius: float) -> np.ndarray:
    """(n, 3) centres of a hexagonal close packing (layers along z, ABAB stacking)."""
    r = radius
    dz = 2.0 * r * np.sqrt(2.0 / 3.0)
    pts = []
    for k in range(int(np.floor((hi[2] - lo[2]) / dz + 1e-9)) + 1):
        layer = hexagonal_2d((lo[0] + (r if k % 2 else 0.0), lo[1] + (r / np.sqrt(3) if k % 2 else 0.0)),
                             (hi[0], hi[1]), r)
        layer[:, 2] = lo[2] + k * dz
        pts.append(layer)
    return np.vstack(pts)


def random_dense(lo, hi, r_mean: float, r_spread: float = 0.2, attempts: int = 200_000,
                 seed: int = 0, plane: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Random sequential placement of non-overlapping spheres with radii uniform in
    r_mean (1 +- r_spread), until ``attempts`` consecutive-try budget is used up.
    Returns (centres (n, 3), radii (n,)). plane: a quasi-2D layer (z = 0)."""
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    dim = 2 if plane else 3
    rmax = r_mean * (1 + r_spread)
    cell = 2 * rmax
    grid: dict[tuple, list[int]] = {}
    xs, rs = [], []
    for _ in range(attempts):
        r = r_mean * (1 + r_spread * rng.uniform(-1, 1))
        x = np.zeros(3)
        x[:dim] = rng.uniform(lo[:dim] + r, hi[:dim] - r)
        key = tuple((x[:dim] // cell).astype(int))
        ok = True
        for off in np.ndindex(*(3,) * dim):
            for i in grid.get(tuple(k + o - 1 for k, o in zip(key, off)), ()):
                if np.sum((xs[i] - x) ** 2) < (rs[i] + r) ** 2:
                    ok = False
                    break
            if not ok:
                break
        if ok:
            grid.setdefault(key, []).append(len(xs))
            xs.append(x)
            rs.append(r)
    return np.array(xs), np.array(rs)


def neighbour_bonds(x: np.ndarray, radius: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """(nb, 2) index pairs i < j whose gap |x_i - x_j| - r_i - r_j is at most tol * (r_i + r_j)
    (touching neighbours of a regular packing; for random packings pass a larger tol)."""
    radius = np.broadcast_to(radius, (len(x),))
    tree = cKDTree(x)
    pairs = np.array(sorted(tree.query_pairs(2 * radius.max() * (1 + tol))), dtype=int).reshape(-1, 2)
    if pairs.size == 0:
        return pairs
    gap = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1) - radius[pairs].sum(axis=1)
    return pairs[gap <= tol * radius[pairs].sum(axis=1)]


def laminate_layers(ply_thickness: float, n_plies: int, length: float, radius: float):
    """Square-lattice layer of a laminate in the x-y plane (y through the thickness) whose rows
    never straddle a ply boundary: ply_thickness must be a whole number of spacings 2r.

    Returns (x (n, 3), ply (n,), bonds (nb, 2), family (nb,)) with family 0 = axial and 1 =
    diagonal bonds inside a ply, 2 = bonds that cross a ply interface (the interlaminar bonds).
    """
    d = 2.0 * radius
    rows = ply_thickness / d
    if abs(rows - round(rows)) > 1e-9 * rows or round(rows) < 1:
        raise ValueError(f"ply thickness {ply_thickness:g} m is not a whole number of particle diameters {d:g} m")
    rows = int(round(rows))
    x = square_2d((0.0, 0.5 * d), (length, n_plies * ply_thickness - 0.5 * d), radius)
    ply = np.minimum((x[:, 1] // ply_thickness).astype(int), n_plies - 1)
    bonds, family = square_bonds(x, radius)
    family = np.where(ply[bonds[:, 0]] != ply[bonds[:, 1]], 2, family)
    return x, ply, bonds, family


def fill_elements(mesh, elements: np.ndarray, r_mean: float, r_spread: float = 0.2, seed: int = 0,
                  attempts: int = 200_000) -> tuple[np.ndarray, np.ndarray]:
    """Random dense quasi-2D packing of the union of 2D FEM ``elements`` of a scikit-fem mesh:
    spheres placed in the elements' bounding box, kept where the whole sphere lies inside the
    union (its centre and four rim points in those elements). Returns (x (n, 3), radii (n,))."""
    elements = np.asarray(elements, int)
    pts = mesh.p[:, mesh.t[:, elements]].reshape(2, -1)
    x, r = random_dense(pts.min(axis=1), pts.max(axis=1), r_mean, r_spread, attempts, seed, plane=True)
    finder = mesh.element_finder()
    keep = np.ones(len(x), bool)
    for dx, dy in ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)):
        q = x[:, :2] + np.column_stack([dx * r, dy * r]) * (1 - 1e-9)
        inside = np.zeros(len(x), bool)
        for k, (a, b) in enumerate(q):
            try:
                inside[k] = finder(np.array([a]), np.array([b]))[0] in set(elements.tolist())
            except ValueError:
                inside[k] = False
        keep &= inside
    return x[keep], r[keep]
