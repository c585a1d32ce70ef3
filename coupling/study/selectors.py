"""Zones as selectors: the footprint of a quarter plate's or block's particle column (zone.shape).

The zone is a column through the whole thickness. Its footprint, in the quarter x, y >= 0:

- ``box``: |x|, |y| <= zone.half_width (whole particle spacings);
- ``cylinder``: x^2 + y^2 <= zone.half_width^2;
- ``impactor``: a cylinder about the impactor's axis of its contact radius (a rod's face, a
  sphere's Hertz radius at its peak force, a pressure load's disc;
  closed_forms.plate_contact_radius and block_contact_radius) plus zone.margin (0: a plate's
  thickness, a block's contact radius, or four particle sizes, the larger: a contact's stress
  field decays over about a plate's thickness, Saint-Venant, and over a few contact radii in a
  half-space).

The FEM over the zone's bounding square [0, w]^2 has mesh.elements_width equal elements per
side; a cylinder's square is rounded up so that each element holds whole particle cells (a
mesh file's elements there must be the cells themselves). An element whose centre the
footprint holds is the zone's: its cells are particles (ply_block.carve), the rest FEM. The
tie is on the particles between the zone's cells and the FEM's: a staircase of element faces
(the particles lie on them, so the kinematic tie holds them exactly).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..params import CaseError


@dataclass
class Footprint:
    """w: m, the bounding square's half side (whole elements and particle spacings); n: FEM
    elements per side of it; radius: m, a cylinder's (inf for a box)."""

    w: float
    n: int
    radius: float

    def inside(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Which points (element centres) the footprint holds."""
        if np.isinf(self.radius):
            return (x < self.w) & (y < self.w)
        return np.hypot(x, y) <= self.radius

    def cells(self, d: float) -> np.ndarray:
        """((N + 1, N + 1) bool, N = w / d + 1 particle columns): the padded cell mask of
        ply_block.carve, cells outside [0, w]^2 not selected."""
        N = int(round(self.w / d)) + 1
        c = (np.arange(N - 1) + 0.5) * d  # cell centres
        h = self.w / self.n
        centre = (np.floor(c / h) + 0.5) * h  # the centre of the element holding each cell
        out = np.zeros((N + 1, N + 1), bool)
        out[1:N, 1:N] = self.inside(centre[:, None], centre[None, :])
        return out


def tie_particles(cells: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """(n,) bool: the particles at columns (i, j) that touch both the zone's cells and the FEM's
    (a padded cell mask of ply_block.carve; the cells beyond the symmetry planes are neither):
    those the tie holds."""
    fem = ~cells
    fem[0, :] = fem[:, 0] = False
    return fem[i, j] | fem[i + 1, j] | fem[i, j + 1] | fem[i + 1, j + 1]


def whole_spacings(p: dict, d: float) -> None:
    """A quarter model's half span and half width must be whole particle spacings d (m)."""
    for key in ("geometry.span", "geometry.width"):
        m = 0.5 * p[key] / d
        if abs(m - round(m)) > 1e-6:
            raise CaseError(f"{key} = {p[key]:g}: its half must be a whole number of particle spacings ({d:g} m); "
                            f"allowed e.g. {2 * max(1, round(m)) * d:g} m")


def footprint(study, p: dict, built, cell_wise: bool = False) -> Footprint:
    """The zone's footprint from zone.shape and its keys; CaseError (one line) when it does not
    fit the plate or does not hold the impactor's face. cell_wise: the FEM's elements over the
    zone's square are its particle cells (a zone that may grow)."""
    d, shape = built.t, p["zone.shape"]
    # a mesh file's elements are matched to the particle cells one by one (its own check); the
    # structured FEM has mesh.elements_width elements of whole cells over the zone's square
    cell_wise = cell_wise or bool(p.get("mesh.file"))
    n = 1 if cell_wise else p["mesh.elements_width"]
    half_side = 0.5 * min(p["geometry.span"], p["geometry.width"])
    key = "zone.margin" if shape == "impactor" else "zone.half_width"
    if shape == "box":
        w = p["zone.half_width"]
        if abs(w / d - round(w / d)) > 1e-6:
            raise CaseError(f"zone.half_width = {w:g}: a whole number of particle spacings ({d:g} m); allowed e.g. "
                            f"{max(1, round(w / d)) * d:g} m")
        fp = Footprint(w, int(round(w / d)) if cell_wise else n, np.inf)
    else:
        if shape == "cylinder":
            radius = p["zone.half_width"]
        else:
            from .closed_forms import block_contact_radius, plate_contact_radius  # (they import the assembler)
            if p["geometry.shape"] == "block":  # a contact's field decays over a few contact radii
                r = block_contact_radius(study, p)
                radius = r + (p["zone.margin"] or max(r, 4 * d))
            else:  # a plate's, over about its thickness (Saint-Venant)
                radius = plate_contact_radius(study, p) + (p["zone.margin"] or max(built.lam.thickness, 4 * d))
        step = n * d  # the square holds n elements of whole particle cells
        w = max(1, np.ceil(radius / step - 1e-9)) * step
        fp = Footprint(w, int(round(w / d)) if cell_wise else n, radius)
        if fp.w >= 0.8 * half_side:
            raise CaseError(f"{key} = {p[key]:g}: the zone's square ({fp.w:g} m, mesh.elements_width = {n} elements "
                            f"of whole particle spacings) reaches past 0.8 x the smaller half side "
                            f"({0.8 * half_side:g} m); allowed: a smaller zone or fewer mesh.elements_width")
    if not 2 * d < min(fp.w, fp.radius) or fp.w >= 0.8 * half_side:
        raise CaseError(f"{key} = {p[key]:g}: the zone's radius or half width ({min(fp.w, fp.radius):g} m) allowed "
                        f"between two particle sizes ({2 * d:g} m) and 0.8 x the smaller half side "
                        f"({0.8 * half_side:g} m)")
    for name, kind in study.layout.names["impactors"].items():
        if kind != "rod":
            continue
        r = p[f"impactors.{name}.radius"]
        if min(fp.w, fp.radius) < r + 2 * d:
            raise CaseError(f"impactors.{name}.radius = {r:g}: the rod's face must stay on the DEM zone; allowed <= "
                            f"the zone's radius less two particle sizes ({min(fp.w, fp.radius) - 2 * d:g} m)")
    return fp
