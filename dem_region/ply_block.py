"""A laminate block (3D) as a cubic particle lattice whose bonds carry the seed's laws.

The 3D sibling of ply_lattice.py (the beam slice). Particles sit on a cubic grid of spacing d:
columns x0 + i d, y0 + j d in the plane and rows z0 + (k + 1/2) d through the thickness, one
or more rows per ply. Inside a ply each particle has three axial bonds (x, y, z) and two
diagonals on each of its three cell faces. For a uniform strain the energy per cell gives
(energy density, bond stiffness k = K x area, area d^2):

    C_xx = a_x + g_xy + g_xz,  C_xy = g_xy,  C_66 = g_xy  (and cyclically)

with a_x = k_x / d of the axial bonds and g_xy = k_xy / d of the xy-face diagonals. The
shear moduli set g (g_xy = G_xy: the lattice's Cauchy relation C_12 = C_66 fixes its Poisson
ratios) and the axial stiffnesses are solved so that the three uniaxial moduli 1 / S_ii are
the ply's E_x, E_y, E_z exactly (scipy's root finder; refused if a stiffness comes out
negative, i.e. a shear modulus too large for a central-force lattice).

Ply angles: 0 has its fibres along x, 90 along y; z is the ply normal (the laminate's
thickness). Intralaminar bonds follow PlyBondLaw (Hoffman, energy-regularised: a crack
normal to x, y or z dissipates the ply's Gf whatever d); the vertical pairs that cross a ply
interface follow HashinCohesiveLaw with the penalty K = E_z / d of the material they replace.

Planes through the block's boundary columns (a symmetry plane, or the face tied to a FEM far
field) cut those particles' cells: the caller passes ``half_planes`` and the particles on
them carry half the mass (a quarter on two), and bonds lying in such a plane half the area.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from physics.laws import HashinCohesiveLaw, PlyBondLaw
from .ply_lattice import PlyMaterial
from .scene import DemScene, check_fits

# the 13 bond directions of a cell: 3 axial, 6 face diagonals, as integer offsets
AXIAL = ((1, 0, 0), (0, 1, 0), (0, 0, 1))
DIAGONAL = ((1, 1, 0), (1, -1, 0), (1, 0, 1), (1, 0, -1), (0, 1, 1), (0, 1, -1))


def ply_axes(angle: float) -> np.ndarray:
    """(3, 3) ply axes (columns 1, 2, 3) in global x, y, z: fibres along x (0) or y (90)."""
    if angle == 0:
        return np.eye(3)
    if angle == 90:
        return np.array([[0, -1.0, 0], [1.0, 0, 0], [0, 0, 1.0]])
    raise ValueError(f"ply angle {angle:g}: allowed 0 or 90 on a cubic lattice")


def engineering(material: PlyMaterial, angle: float) -> tuple[np.ndarray, np.ndarray]:
    """((E_x, E_y, E_z), (G_yz, G_xz, G_xy)) Pa of a ply at ``angle`` in global axes."""
    E11, E22, G12, G23 = material.E11, material.E22, material.G12, material.G23
    if angle == 0:
        return np.array([E11, E22, E22]), np.array([G23, G12, G12])
    return np.array([E22, E11, E22]), np.array([G12, G23, G12])


def stiffness(a: np.ndarray, g: np.ndarray) -> np.ndarray:
    """(3, 3) normal block of the lattice's stiffness for axial a (3,) and face g (G_yz, G_xz, G_xy) Pa."""
    g_yz, g_xz, g_xy = g
    return np.array([[a[0] + g_xy + g_xz, g_xy, g_xz],
                     [g_xy, a[1] + g_xy + g_yz, g_yz],
                     [g_xz, g_yz, a[2] + g_xz + g_yz]])


def calibrate(E: np.ndarray, G: np.ndarray) -> np.ndarray:
    """(3,) Pa, axial stiffnesses a = k / d such that the lattice's uniaxial moduli are E (3,)
    with face diagonals g = G (G_yz, G_xz, G_xy)."""
    E, G = np.asarray(E, float), np.asarray(G, float)

    def residual(a):
        return 1.0 / np.diag(np.linalg.inv(stiffness(a, G))) / E - 1.0

    a = optimize.root(residual, E.copy(), tol=1e-14).x
    if np.any(a <= 0) or np.max(np.abs(residual(a))) > 1e-10:
        raise ValueError(f"no central-force cubic lattice has moduli E = {E.tolist()} Pa with shear moduli "
                         f"{G.tolist()} Pa (axial stiffness {a.tolist()}): shear moduli too large")
    return a


@dataclass
class PlyBlock:
    """x (n, 3) m; radius m; density (n,) kg/m^3 of the spheres (cell mass / sphere volume);
    ply (n,), index (n, 3) lattice indices (i, j, k); volume (n,) m^3 of each particle's cell;
    intra_pairs (ni, 2), intra_area (ni,) m^2, intra_law; inter_pairs (nj, 2), inter_area,
    inter_K Pa/m, inter_along (nj, 4): the neighbouring interface pairs at -x, +x, -y, +y
    (-1 at an edge)."""

    x: np.ndarray
    radius: float
    density: np.ndarray
    ply: np.ndarray
    index: np.ndarray
    volume: np.ndarray
    intra_pairs: np.ndarray
    intra_area: np.ndarray
    intra_law: PlyBondLaw
    inter_pairs: np.ndarray
    inter_area: np.ndarray
    inter_K: float
    inter_along: np.ndarray
    d: float

    @property
    def n(self) -> int:
        return len(self.x)


def build(origin, n_columns: tuple[int, int], rows_per_ply: list[int], angles: list[float], d: float,
          material: PlyMaterial, half_planes=()) -> PlyBlock:
    """Block of n_columns (nx, ny) columns at origin + (i d, j d) and rows origin_z + (k + 1/2) d,
    the first rows_per_ply[0] rows in ply 0 (angle angles[0]) and so on. half_planes: pairs
    (axis, index), e.g. (0, 0) for the plane x = origin_x: cells cut in half there."""
    nx, ny = n_columns
    ply_of_row = np.repeat(np.arange(len(rows_per_ply)), rows_per_ply)
    nz = len(ply_of_row)
    check_fits(float(nx) * ny * nz, f"ply block of {nx} x {ny} x {nz} particles (spacing {d:g} m)")
    I, J, K = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"))
    index = np.column_stack([I, J, K])
    x = np.asarray(origin, float) + d * (index + np.array([0.0, 0.0, 0.5]))
    flat = lambda i, j, k: (i * ny + j) * nz + k
    cut = np.ones((len(x), 3))  # per axis: 0.5 on a half plane
    for axis, at in half_planes:
        cut[index[:, axis] == at, axis] = 0.5
    volume = d**3 * cut.prod(axis=1)

    # per ply: axial (a) and face (g) stiffness per volume, fracture energy shares
    Kb, Gf, axes, pairs = [], [], [], []
    for p_, angle in enumerate(angles):
        E, G = engineering(material, angle)
        a = calibrate(E, G)
        g = {(0, 1): G[2], (0, 2): G[1], (1, 2): G[0]}  # face plane -> its diagonals' g
        total = np.array([a[0] + G[2] + G[1], a[1] + G[2] + G[0], a[2] + G[1] + G[0]])  # C_ii
        # Gf of a crack normal to x, y, z: fibre cracks across the fibre axis, matrix cracks otherwise
        fibre = 0 if angle == 0 else 1
        Gf_dir = np.array([material.Gf_fibre if k == fibre else material.Gf_matrix for k in range(3)])
        in_ply = ply_of_row[K] == p_
        for off in AXIAL + DIAGONAL:
            o = np.array(off)
            I2, J2, K2 = I + o[0], J + o[1], K + o[2]
            ok = in_ply & (I2 >= 0) & (I2 < nx) & (J2 >= 0) & (J2 < ny) & (K2 >= 0) & (K2 < nz)
            ok[ok] &= ply_of_row[K2[ok]] == p_
            i0 = np.flatnonzero(ok)
            i1 = flat(I2[ok], J2[ok], K2[ok])
            pairs.append(np.column_stack([i0, i1]))
            axes_on = np.flatnonzero(o)
            if len(axes_on) == 1:  # axial: k = a d, per area d^2
                k_ = axes_on[0]
                Kb.append(np.full(len(i0), a[k_] / d))
                share = np.zeros(3)
                share[k_] = a[k_] / total[k_]
            else:  # face diagonal of length sqrt(2) d: k = g d
                gk = g[tuple(axes_on)]
                Kb.append(np.full(len(i0), gk / d))
                share = np.zeros(3)
                share[axes_on] = 0.5 * gk / total[axes_on]  # two diagonals per face share the cut
            Gf.append(np.tile(Gf_dir * share, (len(i0), 1)))
            axes.append(np.broadcast_to(ply_axes(angle), (len(i0), 3, 3)))
    intra = np.vstack(pairs)
    law = PlyBondLaw(np.concatenate(Kb), np.vstack(Gf), material.strengths, np.concatenate(axes))
    # a crack normal to a direction no bond of this family crosses dissipates nothing through it:
    # give those columns the bond's own smallest non-zero share (brittle otherwise)
    gf = law.Gf
    positive = np.where(gf > 0, gf, np.inf).min(axis=1)
    law.Gf = np.where(gf > 0, gf, positive[:, None])
    area = d**2 * _in_plane_factor(index, cut, intra)

    # interlaminar pairs: vertical, across each change of ply; numbered column by column (the
    # interfaces of a column together), as the particles are, so that a pass over the bonds
    # reads the particles in order
    rows = np.flatnonzero(ply_of_row[:-1] != ply_of_row[1:])
    R = len(rows)
    ii, jj, kk = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), rows, indexing="ij"))
    inter = np.column_stack([flat(ii, jj, kk), flat(ii, jj, kk + 1)]).reshape(-1, 2)
    m = np.arange(len(inter))
    along = np.column_stack([np.where(ii > 0, m - ny * R, -1), np.where(ii < nx - 1, m + ny * R, -1),
                             np.where(jj > 0, m - R, -1), np.where(jj < ny - 1, m + R, -1)]).reshape(-1, 4)
    E_z = min(engineering(material, a)[0][2] for a in angles)
    sphere = 4.0 / 3.0 * np.pi * (d / 2) ** 3
    return PlyBlock(x, d / 2, material.rho * volume / sphere, ply_of_row[K], index, volume, intra, area, law,
                    inter, d**2 * _in_plane_factor(index, cut, inter), E_z / d, along, d)


def _in_plane_factor(index: np.ndarray, cut: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """(nb,) share of a bond's area inside the block: 1/2 per half plane that holds both ends."""
    f = np.ones(len(pairs))
    for axis in range(3):
        same = index[pairs[:, 0], axis] == index[pairs[:, 1], axis]
        f *= np.where(same, cut[pairs[:, 0], axis], 1.0)
    return f


def interlaminar_law(block: PlyBlock, Z0: float, R0: float, GIc: float, GIIc: float, eta: float = 2.284,
                     mixed_mode: str = "bk") -> HashinCohesiveLaw:
    return HashinCohesiveLaw(K=block.inter_K, Z0=Z0, R0=R0, GIc=GIc, GIIc=GIIc, eta=eta, mixed_mode=mixed_mode)


def engine_scene(block: PlyBlock, **kw) -> DemScene:
    """The engine's view of a block: particles, and a placeholder bond (1e-9 of the stiffest
    law bond) on every law pair so that the engine adds no contact of its own between them."""
    K_max = float(np.max(block.intra_law.K))
    return DemScene(block.x, block.radius, block.density, np.vstack([block.intra_pairs, block.inter_pairs]),
                    kn=1e-9 * K_max * block.d**2, ks=0.0, young=K_max * block.d, placeholder_bonds=True, **kw)


def carve(block: PlyBlock, cells: np.ndarray) -> tuple[PlyBlock, np.ndarray]:
    """The part of a block (built without half planes) that selected in-plane cells hold: a zone
    of any footprint on the block's grid (a cylinder, a staircase about an impactor).

    cells: (nx + 1, ny + 1) bool; cell (a, b) is the d x d square between particle columns
    a - 1 and a along x and b - 1 and b along y (so the first and last cell of each axis lie
    outside the block's columns), True where the zone's material is. A particle stands for the
    share of the four cells about its column that are selected (its mass), a bond for the share
    of the cells along its segment (its area): a vertical bond lies among four cells, an axial
    bond in the plane or a diagonal in a vertical face between two, a diagonal in the plane
    inside one. A symmetry plane or a face tied to the FEM is thus a half cell, as half_planes
    makes it. Returns (the carved block, the kept particles' old indices (n,))."""
    cells = np.asarray(cells, float)
    i, j = block.index[:, 0], block.index[:, 1]
    frac = 0.25 * (cells[i, j] + cells[i + 1, j] + cells[i, j + 1] + cells[i + 1, j + 1])
    kept = np.flatnonzero(frac > 0)
    new = np.full(block.n, -1)
    new[kept] = np.arange(kept.size)

    def share(pairs):
        a, b = block.index[pairs[:, 0]], block.index[pairs[:, 1]]
        total = np.zeros(len(pairs))
        spans = []
        for axis in (0, 1):  # a segment along the axis crosses one cell, or lies between two
            lo = np.minimum(a[:, axis], b[:, axis])
            same = a[:, axis] == b[:, axis]
            spans.append([(np.where(same, lo, lo + 1), 1.0), (lo + 1, np.where(same, 1.0, 0.0))])
        weight = np.zeros(len(pairs))
        for ca, wa in spans[0]:
            for cb, wb in spans[1]:
                w = wa * wb
                total += w * cells[ca, cb]
                weight += w
        return total / weight

    f_intra, f_inter = share(block.intra_pairs), share(block.inter_pairs)
    keep_intra, keep_inter = np.flatnonzero(f_intra > 0), np.flatnonzero(f_inter > 0)
    law = block.intra_law
    sub = PlyBondLaw(law.K[keep_intra], law.Gf[keep_intra], law.strengths, law.axes[keep_intra])
    inter = new[block.inter_pairs[keep_inter]]
    # the interface pairs' in-plane neighbours (-x, +x, -y, +y) among the kept ones
    ij = block.index[block.inter_pairs[keep_inter, 0]]
    lookup = {tuple(r): m for m, r in enumerate(ij.tolist())}
    along = np.array([[lookup.get((r[0] + di, r[1] + dj, r[2]), -1)
                       for di, dj in ((-1, 0), (1, 0), (0, -1), (0, 1))] for r in ij.tolist()], int).reshape(-1, 4)
    d = block.d
    carved = PlyBlock(block.x[kept], block.radius, block.density[kept] * frac[kept], block.ply[kept],
                      block.index[kept], block.volume[kept] * frac[kept], new[block.intra_pairs[keep_intra]],
                      d**2 * f_intra[keep_intra], sub, inter, d**2 * f_inter[keep_inter], block.inter_K, along, d)
    return carved, kept
