"""A laminate slice as a square particle lattice whose bonds carry the seed's laws.

Rows of particles (spacing d, slice thickness t = d) stack through the thickness (y), one or
more rows per ply; columns run along the beam (x). Inside a ply the lattice has axial bonds
along x and y and two diagonals per cell, set from the ply's in-plane constants by the
closed form of calibration.py: C_xx = (k_x + k_2) / t, C_yy = (k_y + k_2) / t, C_66 = k_2 / t,
with k_2 = G t, k_x = (E_x + G^2 / E_y - G) t, k_y = (E_y + G^2 / E_x - G) t, so the uniaxial
moduli are E_x and E_y (the Poisson ratio is the lattice's G / E, not the ply's). For a 0 ply
(fibres along x) E_x = E11, E_y = E22, G = G12; for a 90 ply of a beam slice the fibres point
out of plane (z) and E_x = E_y = E22, G = G23.

Intralaminar bonds (all three families) follow PlyBondLaw (Hoffman, energy-regularised);
the vertical pairs that cross a ply interface follow HashinCohesiveLaw with the penalty
K = E_y / d of the material they replace (no diagonals cross an interface). The engine gets
every law pair as a placeholder bond (1e-9 of the stiffness) so that it adds no contact of
its own between them; it integrates the particles and handles contact between fragments.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from physics.failure import HoffmanStrengths

from physics.laws import PlyBondLaw
from .scene import check_fits


@dataclass(frozen=True)
class PlyMaterial:
    """Transversely isotropic ply (Pa, kg/m^3) with Hoffman strengths (Pa) and fracture
    energies (J/m^2) of a crack across the fibres (Gf_fibre) and along them (Gf_matrix)."""

    E11: float
    E22: float
    G12: float
    G23: float
    rho: float
    strengths: HoffmanStrengths
    Gf_fibre: float
    Gf_matrix: float
    moduli: dict | None = None  # angle -> (E_x, E_y, G) of the slice, e.g. from a plane-strain D

    def in_plane(self, angle: float) -> tuple[float, float, float]:
        """(E_x, E_y, G) of the slice for ply angle 0 (fibres along x) or 90 (out of plane);
        the uniaxial in-plane moduli of the FEM's reduced matrix if given (same slice on
        both sides of the interface), else the plane-stress engineering constants."""
        if self.moduli is not None:
            return self.moduli[angle]
        return (self.E11, self.E22, self.G12) if angle == 0 else (self.E22, self.E22, self.G23)

    def axes(self, angle: float) -> np.ndarray:
        """(3, 3) ply axes (columns 1, 2, 3) in global x, y, z."""
        if angle == 0:  # 1 = x, 2 = z (in-ply transverse, across the width), 3 = y (ply normal)
            return np.array([[1.0, 0, 0], [0, 0, 1.0], [0, 1.0, 0]])
        return np.array([[0, 1.0, 0], [0, 0, 1.0], [1.0, 0, 0]])  # 1 = z, 2 = x, 3 = y


def slice_moduli(D: np.ndarray) -> tuple[float, float, float]:
    """(E_x, E_y, G) Pa, the uniaxial moduli and shear modulus of a 2D stiffness (3, 3)
    [xx, yy, xy] (plane strain or stress): 1 / compliance diagonal, and D_66."""
    S = np.linalg.inv(D)
    return 1.0 / S[0, 0], 1.0 / S[1, 1], float(D[2, 2])


def lattice_stiffness(E_x: float, E_y: float, G: float, t: float) -> tuple[float, float, float]:
    """(k_x, k_y, k_2) N/m of a square lattice cell of slice thickness t."""
    if G >= min(E_x, E_y):
        raise ValueError(f"shear modulus {G:g} Pa must be below both moduli ({E_x:g}, {E_y:g} Pa) for a square lattice")
    return (E_x + G**2 / E_y - G) * t, (E_y + G**2 / E_x - G) * t, G * t


@dataclass
class PlyLattice:
    """x (n, 3) m, radius m, sphere density (n,) kg/m^3, ply (n,) index of each particle's
    ply, column / row (n,) lattice indices; ``intra`` and ``inter``: (pairs, K, area, ...) of
    the two bond sets; ``engine_pairs``, ``engine_k``: what the engine builds."""

    x: np.ndarray
    radius: float
    density: np.ndarray
    ply: np.ndarray
    column: np.ndarray
    row: np.ndarray
    intra_pairs: np.ndarray
    intra_law: PlyBondLaw
    inter_pairs: np.ndarray
    inter_K: float
    d: float
    inter_along: np.ndarray | None = None  # (ni, 2) neighbour pairs along each interface

    @property
    def n(self) -> int:
        return len(self.x)

    def cell_volume(self) -> np.ndarray:
        return np.full(self.n, self.d**3)


def build(x0: float, n_columns: int, y0: float, rows_per_ply: list[int], angles: list[float], d: float,
          material: PlyMaterial) -> PlyLattice:
    """Lattice with columns x0 + k d (k < n_columns) and rows y0 + (j + 1/2) d, the first
    rows_per_ply[0] rows in ply 0 (angle angles[0]) and so on."""
    ply_of_row = np.repeat(np.arange(len(rows_per_ply)), rows_per_ply)
    n_rows = len(ply_of_row)
    check_fits(float(n_columns) * n_rows, f"ply lattice of {n_columns} x {n_rows} particles (spacing {d:g} m)")
    col, row = np.meshgrid(np.arange(n_columns), np.arange(n_rows), indexing="ij")
    col, row = col.ravel(), row.ravel()
    x = np.column_stack([x0 + d * col, y0 + d * (row + 0.5), np.zeros(col.size)])
    idx = lambda c, j: c * n_rows + j
    t = d
    pairs, K, Gf, axes = [], [], [], []
    for p_, angle in enumerate(angles):
        kx, ky, k2 = lattice_stiffness(*material.in_plane(angle), t)
        # crack across x (normal x) and across y: energies shared by the families it cuts
        G_x = material.Gf_fibre if angle == 0 else material.Gf_matrix  # crack normal to x
        G_y = material.Gf_matrix
        rows = np.flatnonzero(ply_of_row == p_)
        for c in range(n_columns):
            for j in rows:
                if c + 1 < n_columns:  # axial x
                    pairs.append((idx(c, j), idx(c + 1, j)))
                    K.append(kx / (d * t))
                    Gf.append((G_x * kx / (kx + k2),) * 2)
                    axes.append(material.axes(angle))
                if j + 1 in rows:  # axial y, and the cell's diagonals
                    pairs.append((idx(c, j), idx(c, j + 1)))
                    K.append(ky / (d * t))
                    Gf.append((G_y * ky / (ky + k2),) * 2)
                    axes.append(material.axes(angle))
                    if c + 1 < n_columns:
                        for a, b in ((idx(c, j), idx(c + 1, j + 1)), (idx(c + 1, j), idx(c, j + 1))):
                            pairs.append((a, b))
                            # a diagonal of length sqrt(2) d with k_2: per area of d t its K is k_2/(d t)
                            K.append(k2 / (d * t))
                            Gf.append((0.5 * G_x * k2 / (kx + k2), 0.5 * G_y * k2 / (ky + k2)))
                            axes.append(material.axes(angle))
    law = PlyBondLaw(np.array(K), np.array(Gf), material.strengths, np.array(axes))
    inter = [(idx(c, j), idx(c, j + 1)) for j in range(n_rows - 1) if ply_of_row[j] != ply_of_row[j + 1]
             for c in range(n_columns)]
    k = np.arange(len(inter))
    c = k % n_columns  # pairs run along each interface row by column
    along = np.column_stack([np.where(c > 0, k - 1, -1), np.where(c < n_columns - 1, k + 1, -1)])
    sphere_rho = material.rho * d**3 / (4.0 / 3.0 * np.pi * (d / 2) ** 3)
    E_y = min(material.in_plane(a)[1] for a in angles)
    return PlyLattice(x, d / 2, np.full(len(x), sphere_rho), ply_of_row[row], col, row,
                      np.array(pairs, int).reshape(-1, 2), law, np.array(inter, int).reshape(-1, 2), E_y / d, d,
                      along)
