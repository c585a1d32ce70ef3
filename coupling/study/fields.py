"""What a study's fields.xdmf holds: the whole structure, far field and zone together.

One frame: the FEM mesh (displacement, velocity; per element strain, stress and the failure
indices the zone's laws use, Hashin interlaminar and Hoffman intralaminar, from the element's
ply), the particles as vertices (displacement, velocity, radius, ply, damage = the largest of
their bonds', broken bonds) and the interlaminar bonds as lines (damage, debonded). ``zone``
is 0 on FEM cells, 1 on particles and bonds, so one ParaView threshold splits them.

A bond is written as a quadratic edge (line3) through a point at its midpoint: meshio 5.3.5
cannot write two-node lines beside other cells (its mixed topology writer fails on them,
meshio/xdmf/time_series.py, "c.data[:] = np.insert(...)"), and a quadratic edge draws the same
segment.
"""
from __future__ import annotations

import numpy as np

from fem_region import materials
from physics.failure import hashin_interlaminar, hoffman, to_ply_axes
from physics.kernels import element_failure_index, hoffman_coefficients

from ..simulation import FieldFrame

CELL = {"quad4": "quad", "tri3": "triangle", "hex8": "hexahedron", "tet4": "tetra"}


def _pad(a: np.ndarray) -> np.ndarray:
    return np.pad(a, ((0, 0), (0, 3 - a.shape[1])))


class FemIndices:
    """Per-element failure indices of a laminate FEM: the element's ply from its centroid's
    height, its 6 x 6 stiffness and ply axes; small-strain centroid strain in, (Hashin
    interlaminar, Hoffman) out."""

    def __init__(self, region, lam, dim: int):
        self.region, self.dim = region, dim
        X = region.X[region.mesh.t.T]  # (nel, nodes, dim)
        run = np.searchsorted(np.cumsum(lam.plies) * lam.ply_thickness, X[:, :, dim - 1].mean(axis=1))
        angles = np.array(lam.angles)[np.minimum(run, len(lam.angles) - 1)]
        axes = {a: materials.ply_axes(a, dim) for a in set(angles)}
        stiffness = {a: lam.stiffness(a, dim) for a in set(angles)}
        self.C = np.array([stiffness[a] for a in angles])  # (nel, 6, 6)
        self.R = np.array([axes[a] for a in angles])  # (nel, 3, 3)
        self.k = lam.strengths()
        self.Z0, self.R0 = lam.interface["Z0"], lam.interface["R0"]

    def ply_stress(self, strain: np.ndarray) -> np.ndarray:
        """(nel, 6) Pa each element's stress in its ply's axes at its centroid strain (nel, ns)."""
        if self.dim == 2:  # plane strain: (xx, yy, xy) -> (xx, yy, zz = 0, yz = 0, xz = 0, xy)
            eps = np.zeros((len(strain), 6))
            eps[:, [0, 1, 5]] = strain
        else:
            eps = strain
        return to_ply_axes(np.einsum("eij,ej->ei", self.C, eps), self.R)

    def __call__(self, strain: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ply = self.ply_stress(strain)
        return hashin_interlaminar(ply, self.Z0, self.R0), hoffman(ply, self.k)


class BondedIndices:
    """Per-element indices of a bonded beam's FEM: Hoffman of the body (its stiffness on the
    centroid strain, its isotropic strengths) and the adhesive's Hashin index on the bottom
    element row, where the sheet is smeared (0 elsewhere)."""

    def __init__(self, region, bb, dim: int):
        self.dim = dim
        C = bb.body_C()
        self.D = C if dim == 3 else materials.plane_stress(C)
        self.R = materials.ply_axes(0.0, dim)
        X = region.X[region.mesh.t.T]
        self.bottom = X[:, :, dim - 1].mean(axis=1) < bb.d / 2
        self.k = bb.body_strengths()
        self.Z0, self.R0 = bb.adhesive["Z0"], bb.adhesive["R0"]

    def ply_stress(self, strain: np.ndarray) -> np.ndarray:
        """(nel, 6) Pa the body's stress at each element's centroid strain (nel, ns)."""
        s = strain @ self.D.T
        if self.dim == 2:  # plane stress: (xx, yy, xy) -> (xx, yy, zz = 0, yz = 0, xz = 0, xy)
            sig = np.zeros((len(s), 6))
            sig[:, [0, 1, 5]] = s
        else:
            sig = s
        return to_ply_axes(sig, self.R)

    def __call__(self, strain: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        ply = self.ply_stress(strain)
        return np.where(self.bottom, hashin_interlaminar(ply, self.Z0, self.R0), 0.0), hoffman(ply, self.k)


class ElementIndex:
    """The growth check's criterion at every element in one compiled pass (a check may come
    at every FEM step): the larger of Hoffman's index where ``hoffman_on`` and Hashin's
    interlaminar index where ``hashin_on`` (nel,) bool, and 0, at the centroid. The ply stress
    is linear in the element's nodal displacement (small strain), so each element's map
    L (6, nd) is ``ply_stress`` (strain (nel, ns) -> (nel, 6) Pa, the criteria's own) of its
    centroid B's columns, taken once."""

    def __init__(self, region, ply_stress, hoffman_on, hashin_on, strengths=None, Z0: float = 1.0,
                 R0: float = 1.0):
        B, self.dofs = region.centroid_B()
        self.L = np.ascontiguousarray(np.stack([ply_stress(B[:, :, j]) for j in range(B.shape[2])], axis=-1))
        k = (1.0,) * 9 if strengths is None else tuple(float(getattr(strengths, f)) for f in
                                                         ("Xt", "Xc", "Yt", "Yc", "Zt", "Zc", "S23", "S13", "S12"))
        self.c = hoffman_coefficients(k)
        n = region.n_elements
        self.hoffman_on = np.ascontiguousarray(np.broadcast_to(hoffman_on, n), np.bool_)
        self.hashin_on = np.ascontiguousarray(np.broadcast_to(hashin_on, n), np.bool_)
        self.Z0, self.R0 = float(Z0), float(R0)
        self.every = np.arange(n)
        self.out = np.empty(n)  # rewritten at every call

    def __call__(self, u: np.ndarray, elements: np.ndarray | None = None) -> np.ndarray:
        """(nel,) the criterion at FEM displacement u (n, dim) m: this object's buffer, at the
        ``elements`` (k,) int given (the others as the last call left them), or at every one."""
        element_failure_index(u.reshape(-1), self.dofs, self.L, self.c, self.hoffman_on, self.Z0, self.R0,
                              self.hashin_on, self.every if elements is None else elements, self.out)
        return self.out


def frames(built):
    """() -> FieldFrame of the structure ``built`` (study/assemble.py) at the current state."""
    dyn, lat, backend = built.dyn, built.lattice, built.backend
    cells, nodes = {}, 0
    if dyn is not None:
        region = dyn.region
        nodes = region.n_nodes
        cells[CELL[region.etype.name]] = region.mesh.t.T
        indices = FemIndices(region, built.lam, built.dim) if built.lam is not None else \
            BondedIndices(region, built.bonded, built.dim)
    if lat is not None:
        inter = built.inter  # None: a body without interfaces (a block)
        pairs = inter.pairs if inter is not None else np.zeros((0, 2), int)
        mids = nodes + lat.n + np.arange(len(pairs))
        cells["vertex"] = (nodes + np.arange(lat.n))[:, None]
        if len(pairs):
            cells["line3"] = np.column_stack([nodes + pairs, mids])
        ply = np.asarray(lat.ply, float)
        bonds = [b for b in (built.intra, inter, getattr(built, "sheet", None)) if b is not None]
    points = np.vstack(([_pad(dyn.region.X)] if dyn is not None else [])
                       + ([lat.x, 0.5 * (lat.x[pairs[:, 0]] + lat.x[pairs[:, 1]])] if lat is not None else []))

    def frame() -> FieldFrame:
        u, v, cd = [], [], {"zone": [], "strain": [], "stress": [], "interlaminar_index": [], "hoffman_index": [],
                            "damage": [], "debonded": []}
        ns = 0
        if dyn is not None:
            strain, stress = dyn.region.centroid_strain_stress(dyn.state.u)
            ns, nel = strain.shape[1], len(strain)
            hashin, hoff = indices(strain)
            u.append(_pad(dyn.state.u))
            v.append(_pad(dyn.state.v))
            cd["zone"].append(np.zeros(nel))
            cd["strain"].append(strain)
            cd["stress"].append(stress)
            cd["interlaminar_index"].append(hashin)
            cd["hoffman_index"].append(hoff)
            cd["damage"].append(np.zeros(nel))
            cd["debonded"].append(np.zeros(nel))
        if lat is not None:
            up, vp = backend.positions() - lat.x, backend.velocities()
            u += [up, 0.5 * (up[pairs[:, 0]] + up[pairs[:, 1]])]
            v += [vp, 0.5 * (vp[pairs[:, 0]] + vp[pairs[:, 1]])]
            damage, broken = np.zeros(lat.n), np.zeros(lat.n)
            for b in bonds:
                for end in (0, 1):
                    np.maximum.at(damage, b.pairs[:, end], b.damage)
                    np.add.at(broken, b.pairs[:, end], b.failed())
            nb = len(pairs)
            for name, per_particle, per_bond in (("zone", np.ones(lat.n), np.ones(nb)),
                                                 ("damage", damage, inter.damage.copy() if nb else np.zeros(0)),
                                                 ("debonded", np.zeros(lat.n),
                                                  inter.failed().astype(float) if nb else np.zeros(0))):
                cd[name] += [per_particle, per_bond]
            for name in ("strain", "stress"):
                cd[name] += [np.zeros((lat.n, ns or 3)), np.zeros((nb, ns or 3))]
            for name in ("interlaminar_index", "hoffman_index"):
                cd[name] += [np.zeros(lat.n), np.zeros(nb)]
            nb = len(pairs)
            point_extra = {"radius": np.concatenate([np.zeros(nodes), lat.radius * np.ones(lat.n), np.zeros(nb)]),
                           "ply": np.concatenate([np.full(nodes, -1.0), ply, np.full(nb, -1.0)]),
                           "broken_bonds": np.concatenate([np.zeros(nodes), broken, np.zeros(nb)])}
        else:
            point_extra = {}
        if dyn is None:  # no FEM block: strain and stress columns follow the lattice's dimension
            cd = {k: w for k, w in cd.items() if k not in ("strain", "stress", "interlaminar_index", "hoffman_index")}
        return FieldFrame(points, cells, {"displacement": np.vstack(u), "velocity": np.vstack(v), **point_extra}, cd)

    return frame
