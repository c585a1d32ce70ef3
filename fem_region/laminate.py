"""Laminates: a layup of plies becomes ply blocks of elements through the thickness.

2D meshes are in the x-y plane with y through the thickness (plane strain / stress, width
out of plane); 3D meshes stack plies along z. Ply index 0 is the bottom ply.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import materials, mesh


@dataclass
class Laminate:
    """angles: fibre angle per ply (deg, bottom up); ply_thickness: m; C_ply: (6, 6) Pa in ply axes."""

    angles: list[float]
    ply_thickness: float
    C_ply: np.ndarray

    @classmethod
    def from_layup(cls, layup: str, ply_thickness: float, C_ply: np.ndarray) -> "Laminate":
        return cls(materials.parse_layup(layup), ply_thickness, C_ply)

    @property
    def thickness(self) -> float:
        return len(self.angles) * self.ply_thickness

    def interfaces(self) -> list[tuple[int, float]]:
        """(index of the ply below, height m) of every interface between plies of different angle."""
        return [(i, (i + 1) * self.ply_thickness) for i in range(len(self.angles) - 1)
                if self.angles[i] != self.angles[i + 1]]

    def ply_of(self, height: np.ndarray) -> np.ndarray:
        """Ply index at heights (m,) measured from the bottom face."""
        return np.clip((np.asarray(height) / self.ply_thickness).astype(int), 0, len(self.angles) - 1)

    def global_C(self, ply: np.ndarray, dim: int) -> np.ndarray:
        """(m, 6, 6) ply stiffness in global axes for ply indices (m,)."""
        table = np.array([materials.rotate(self.C_ply, materials.ply_axes(a, dim)) for a in self.angles])
        return table[ply]

    def axes(self, ply: np.ndarray, dim: int) -> np.ndarray:
        """(m, 3, 3) ply axes (columns fibre, transverse, normal) for ply indices (m,)."""
        return np.array([materials.ply_axes(a, dim) for a in self.angles])[ply]


def beam_mesh_2d(length: float, lam: Laminate, nx: int, per_ply: int = 1, element: str = "quad4",
                 grade_ratio: float = 1.0, grade_toward: float | None = None):
    """Structured 2D laminated beam [0, length] x [0, thickness]; returns (mesh, ply (nel,)).

    Elements never straddle a ply boundary, so inter-ply interfaces are mesh lines; along x
    the size grows by ``grade_ratio`` per element away from ``grade_toward``.
    """
    xs = mesh.graded(0.0, length, nx, grade_ratio, grade_toward)
    ys = np.linspace(0.0, lam.thickness, len(lam.angles) * per_ply + 1)
    m = mesh.rectangle(xs, ys, element)
    centroid_y = m.p[1, m.t].mean(axis=0)
    return m, lam.ply_of(centroid_y)


def plate_mesh_3d(lx: float, ly: float, lam: Laminate, nx: int, ny: int, per_ply: int = 1,
                  element: str = "hex8", grade_ratio: float = 1.0, center: tuple[float, float] | None = None):
    """Structured laminated plate [0, lx] x [0, ly] x [0, thickness], plies stacked along z,
    graded in x and y towards ``center``; returns (mesh, ply (nel,))."""
    cx, cy = center if center is not None else (None, None)
    xs = mesh.graded(0.0, lx, nx, grade_ratio, cx)
    ys = mesh.graded(0.0, ly, ny, grade_ratio, cy)
    zs = np.linspace(0.0, lam.thickness, len(lam.angles) * per_ply + 1)
    m = mesh.box(xs, ys, zs, element)
    return m, lam.ply_of(m.p[2, m.t].mean(axis=0))
