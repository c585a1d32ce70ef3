"""FemRegion: a mesh, an element type and per-element materials tied into explicit operators.

Nodal arrays are (n_nodes, dim) in SI units; the flat DOF index of node a, component i is
``a * dim + i``. In 2D every volume integral carries the out-of-plane ``thickness``, so forces
are in N and masses in kg.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import skfem
from scipy.sparse._sparsetools import csr_matvec  # y += A x in place: scipy's kernel behind K @ x

from .elements import ElementType
from .hourglass import HourglassControl
from .kernels import (VOIGT_2D, VOIGT_3D, add_hourglass_force, smallest_det_F, total_lagrangian_energy,
                      total_lagrangian_force)
from .materials import voigt_blocks

INTEGRATIONS = ("full", "selective", "reduced")
FORMULATIONS = ("linear", "total_lagrangian")


def sparse_times(A: sp.csr_matrix, u: np.ndarray, out: np.ndarray) -> np.ndarray:
    """out (n, dim) <- A u for u (n, dim), A (n dim, n dim) CSR: scipy's own kernel (the one
    behind ``A @ u``, so the same digits) into the buffer, where ``A @ u`` allocates its result."""
    if not out.flags.c_contiguous:  # (a reshaped copy would take the result)
        raise ValueError("sparse_times: out must be C-contiguous")
    y = out.reshape(-1)
    y[:] = 0.0  # the kernel adds A x to y
    csr_matvec(A.shape[0], A.shape[1], A.indptr, A.indices, A.data, np.ascontiguousarray(u, float).reshape(-1), y)
    return out


def strain_displacement(dN: np.ndarray) -> np.ndarray:
    """dN (..., n_loc, dim) 1/m -> small-strain B (..., n_strain, n_loc * dim), Voigt order."""
    *lead, nloc, dim = dN.shape
    ns = 3 if dim == 2 else 6
    B = np.zeros((*lead, ns, nloc, dim))
    for i in range(dim):
        B[..., i, :, i] = dN[..., i]
    pairs = [(0, 1)] if dim == 2 else [(1, 2), (0, 2), (0, 1)]
    for s, (i, j) in enumerate(pairs, start=dim):
        B[..., s, :, i] = dN[..., j]
        B[..., s, :, j] = dN[..., i]
    return B.reshape(*lead, ns, nloc * dim)


@dataclass
class Quadrature:
    """Shape-function data of one integration rule on every element.

    N: (nel, nqp, n_loc) -; dN: (nel, nqp, n_loc, dim) 1/m; dx: (nel, nqp) m^3 (thickness
    included in 2D); voigt: which Voigt components this rule integrates (selective schemes
    integrate normal and shear parts with different rules).
    """

    N: np.ndarray
    dN: np.ndarray
    dx: np.ndarray
    voigt: list[int]


def _hex8_shear_rules(mesh, etype: ElementType, thickness: float, shear: list[int]) -> list[Quadrature]:
    """Selective integration of hexahedra's shear strains yz, xz, xy (Voigt order ``shear``):
    each at the centre of its own plane and at two Gauss points along the third axis. At the
    centroid alone the twist modes (u_x = a y z, u_y = b x z, u_z = c x y) carry no energy:
    nine zero modes, not six; a 3D beam's sublaminates slid apart on them once their cohesive
    interface softened (debonded 40 % sooner than the converged lattice). This rule keeps each
    shear strain free of locking in bending in its own plane and gives the twists their
    stiffness. The reference axis that runs along each physical axis is read from each
    element's edges (a mesh's elements may be numbered in different orientations)."""
    X = mesh.p.T[mesh.t.T]  # (nel, 8, 3) m
    doflocs = etype.element_cls().doflocs  # (8, 3) the reference corners in [0, 1]^3
    edges = np.einsum("ear,eai->eri", doflocs[None] - 0.5, X)  # (nel, reference axis, physical)
    ref_of = np.argmax(np.abs(edges), axis=1)  # (nel, physical axis) -> the reference axis most along it
    g = 0.5 / np.sqrt(3.0)
    rules = []
    for third, s in zip(range(3), shear):  # yz: two points along x; xz: along y; xy: along z
        N = dN = dx = None
        for r in range(3):
            elements = np.flatnonzero(ref_of[:, third] == r)
            if not elements.size:
                continue
            Xq = np.full((3, 2), 0.5)
            Xq[r] = (0.5 - g, 0.5 + g)
            q = _quadrature(mesh, etype, (Xq, np.array([0.5, 0.5])), thickness, [s], elements)
            if N is None:
                N, dN, dx = (np.zeros((mesh.t.shape[1],) + a.shape[1:]) for a in (q.N, q.dN, q.dx))
            N[elements], dN[elements], dx[elements] = q.N, q.dN, q.dx
        rules.append(Quadrature(N, dN, dx, [s]))
    return rules


def _quadrature(mesh, etype: ElementType, rule, thickness: float, voigt: list[int], elements=None) -> Quadrature:
    """The rule on every element (or on ``elements`` only: arrays of those, in their order)."""
    kw = {"quadrature": rule} if isinstance(rule, tuple) else {"intorder": rule}
    basis = skfem.Basis(mesh, etype.element_cls(), elements=elements, **kw)
    N = np.stack([np.asarray(b[0]) for b in basis.basis], axis=-1)  # (nel, nqp, nloc)
    dN = np.stack([b[0].grad for b in basis.basis], axis=-1)  # (dim, nel, nqp, nloc)
    return Quadrature(N, np.ascontiguousarray(np.moveaxis(dN, 0, -1)), basis.dx * thickness, voigt)  # (the kernels stream it)


@dataclass
class FemRegion:
    """Explicit-dynamics operators of one FEM region.

    mesh: skfem mesh (coordinates ``mesh.p`` (dim, n_nodes) m); D: (nel, ns, ns) Pa, the
    plane (2D) or 3D constitutive matrix per element; rho: (nel,) kg/m^3; thickness: m,
    out-of-plane width in 2D (1 in 3D); integration: "full", "selective" (normal strains
    fully integrated, shear at the centroid: removes shear locking in bending, needs a D
    without normal-shear coupling) or "reduced" (one point, with hourglass control of form
    ``hourglass`` and coefficient ``hourglass_kappa``); formulation: "linear" (small strain,
    assembled K) or "total_lagrangian" (St Venant-Kirchhoff, large rotations; the hourglass
    force stays small-strain).
    """

    mesh: skfem.Mesh
    etype: ElementType
    D: np.ndarray
    rho: np.ndarray
    thickness: float = 1.0
    integration: str = "full"
    formulation: str = "linear"
    hourglass: str = "stiffness"
    hourglass_kappa: float = 0.1
    rules: list[Quadrature] = field(init=False)
    mass: np.ndarray = field(init=False)  # (n_nodes,) kg, lumped
    K: sp.csr_matrix = field(init=False)  # (ndof, ndof) N/m, small-strain stiffness

    def __post_init__(self):
        dim, nel = self.dim, self.n_elements
        self.D = np.broadcast_to(np.asarray(self.D, float), (nel,) + np.shape(self.D)[-2:]).copy()
        self.rho = np.broadcast_to(np.asarray(self.rho, float), (nel,)).copy()
        normal, shear = voigt_blocks(dim)
        full = _quadrature(self.mesh, self.etype, self.etype.full_order, self.thickness, normal + shear)
        if self.integration == "full":
            self.rules = [full]
        elif self.integration == "selective":
            coupling = np.abs(self.D[:, normal][:, :, shear]).max()
            if coupling > 1e-12 * np.abs(self.D).max():
                raise ValueError("integration = 'selective' needs materials without normal-shear "
                                 "coupling (off-axis plies in 3D have it): use 'full'")
            full.voigt = normal
            if self.etype.name == "hex8":  # each shear strain on its own rule (below)
                a, b = np.triu_indices(3, 1)  # the shear-shear terms a split rule would drop
                if np.abs(self.D[:, np.take(shear, a), np.take(shear, b)]).max() > 1e-12 * np.abs(self.D).max():
                    raise ValueError("integration = 'selective' needs materials without coupling between the "
                                     "shear strains (off-axis plies in 3D have it): use 'full'")
                self.rules = [full] + _hex8_shear_rules(self.mesh, self.etype, self.thickness, shear)
            else:
                one = _quadrature(self.mesh, self.etype, self.etype.one_point_rule(), self.thickness, shear)
                self.rules = [full, one]
        elif self.integration == "reduced":
            self.rules = [_quadrature(self.mesh, self.etype, self.etype.one_point_rule(), self.thickness, normal + shear)]
        else:
            raise ValueError(f"integration {self.integration!r}: allowed {INTEGRATIONS}")
        if self.formulation not in FORMULATIONS:
            raise ValueError(f"formulation {self.formulation!r}: allowed {FORMULATIONS}")
        self.mass = np.bincount(self.mesh.t.ravel(),
                                np.einsum("eqa,e,eq->ae", full.N, self.rho, full.dx).ravel(),
                                minlength=self.n_nodes)  # row-sum lumping: sums to the exact mass
        self._edofs = (self.mesh.t.T[:, :, None] * dim + np.arange(dim)).reshape(nel, -1)
        self.hg = None
        if self.integration == "reduced" and self.etype.name in ("quad4", "hex8"):
            one = self.rules[0]
            self.hg = HourglassControl.build(self.X[self.mesh.t.T], one.dN[:, 0], one.dx[:, 0], self.D, self.rho,
                                             self.etype.element_cls().doflocs, self.hourglass, self.hourglass_kappa)
        self.ke = self._element_stiffness()
        self._conn = np.ascontiguousarray(self.mesh.t.T)
        self._D_rules = [np.ascontiguousarray(self._masked_D(q.voigt)) for q in self.rules]
        self.K = self._assemble(self.ke)

    # -- sizes -----------------------------------------------------------------------------
    @property
    def dim(self) -> int:
        return self.mesh.p.shape[0]

    @property
    def n_nodes(self) -> int:
        return self.mesh.p.shape[1]

    @property
    def n_elements(self) -> int:
        return self.mesh.t.shape[1]

    @property
    def ndof(self) -> int:
        return self.n_nodes * self.dim

    @property
    def X(self) -> np.ndarray:
        """(n_nodes, dim) m, reference coordinates (a C-contiguous copy of mesh.p.T, made once:
        the coupled step adds it to u at every DEM step)."""
        p = self.mesh.p
        if getattr(self, "_X_of", None) is not p:
            self._X, self._X_of = np.ascontiguousarray(p.T), p
        return self._X

    def _masked_D(self, voigt: list[int]) -> np.ndarray:
        Dm = np.zeros_like(self.D)
        Dm[:, np.ix_(voigt, voigt)[0], np.ix_(voigt, voigt)[1]] = self.D[:, voigt][:, :, voigt]
        return Dm

    def _element_stiffness(self) -> np.ndarray:
        """(nel, n_loc*dim, n_loc*dim) N/m small-strain element stiffness."""
        ke = 0.0
        for q in self.rules:
            B = strain_displacement(q.dN)
            # contracted pairwise (optimize): the four-operand loop took 5.8 s on 4,800 Hex8
            ke = ke + np.einsum("eqsa,est,eqtb,eq->eab", B, self._masked_D(q.voigt), B, q.dx, optimize=True)
        if self.hg is not None:
            ke = ke + self.hg.stiffness(self.dim)
        return ke

    # -- explicit operators ------------------------------------------------------------------
    def element_masses(self) -> np.ndarray:
        """(nel, n_loc) kg: each element's row-sum lumped mass at its nodes."""
        q = self.rules[0]
        return np.einsum("eqa,e,eq->ea", q.N, self.rho, q.dx)

    def element_critical_dt(self) -> np.ndarray:
        """(nel,) s: 2 / omega_max of each element with its own lumped mass.

        Irons' theorem: the assembled omega_max is at most the largest element omega_max of
        k_e phi = omega^2 m_e phi, so min over elements bounds the central-difference step.
        """
        if not hasattr(self, "_dt_e"):
            me = np.repeat(self.element_masses(), self.dim, axis=1)
            s = 1.0 / np.sqrt(me)
            lam = np.linalg.eigvalsh(self.ke * s[:, :, None] * s[:, None, :])[:, -1]
            self._dt_e = 2.0 / np.sqrt(lam)
        return self._dt_e

    def critical_dt(self, density_scale: np.ndarray | None = None) -> float:
        """Stable central-difference step (s); density_scale (nel,) for mass-scaled elements."""
        dt_e = self.element_critical_dt()
        return float((dt_e if density_scale is None else dt_e * np.sqrt(density_scale)).min())

    def mass_scaling(self, dt_target: float) -> tuple[np.ndarray, np.ndarray]:
        """Selective mass scaling: (density_scale (nel,), added nodal mass (n_nodes,) kg) that
        raise every element's stable step to at least dt_target."""
        f = np.maximum(1.0, (dt_target / self.element_critical_dt()) ** 2)
        added = np.bincount(self.mesh.t.T.ravel(), ((f - 1.0)[:, None] * self.element_masses()).ravel(),
                            minlength=self.n_nodes)
        return f, added

    def internal_force(self, u: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """u: (n_nodes, dim) m -> internal nodal force (n_nodes, dim) N, into ``out`` if given
        (nothing allocated). The linear form is the sparse product by scipy's own CSR kernel
        (a numba loop of the same sums in the same order took 1.4-1.8 x as long; ``K @ u``, the
        same kernel, allocates its result)."""
        if self.formulation == "linear":
            if out is None:
                return (self.K @ u.ravel()).reshape(u.shape)
            return sparse_times(self.K, u, out)
        f = np.zeros(np.shape(u)) if out is None else out
        if out is not None:
            f[:] = 0.0
        voigt = VOIGT_2D if self.dim == 2 else VOIGT_3D
        uc = np.ascontiguousarray(u, dtype=float)
        for q, Dq in zip(self.rules, self._D_rules):
            total_lagrangian_force(uc, self._conn, q.dN, q.dx, Dq, voigt, f)
        if self.hg is not None and self.hg.form == "stiffness":
            add_hourglass_force(self.hg.gamma, self.hg.k, self._conn, uc, 1.0, f)
        return f

    def stiffness_times(self, u: np.ndarray, out: np.ndarray) -> np.ndarray:
        """out (n_nodes, dim) <- K u for u (n_nodes, dim) (the small-strain stiffness, whatever the
        formulation: stiffness-proportional damping), nothing allocated."""
        return sparse_times(self.K, u, out)

    def element_force(self, elements: np.ndarray):
        """The internal force of the elements ``elements`` (k,) alone, as a function
        u (n_nodes, dim) m -> (n_nodes, dim) N; with every element it is ``internal_force``.
        Precomputed (a sparse stiffness, or the sliced kernel data); either form writes into one
        buffer of its own, overwritten by the next call: no allocation per call."""
        e = np.asarray(elements, int)
        f = np.zeros((self.n_nodes, self.dim))
        if self.formulation == "linear":
            K = self._assemble(self.ke[e], e)
            return lambda u: sparse_times(K, u, f)
        voigt = VOIGT_2D if self.dim == 2 else VOIGT_3D
        conn = np.ascontiguousarray(self._conn[e])
        rules = [(np.ascontiguousarray(q.dN[e]), np.ascontiguousarray(q.dx[e]), np.ascontiguousarray(D[e]))
                 for q, D in zip(self.rules, self._D_rules)]
        hg = self.hg if self.hg is not None and self.hg.form == "stiffness" else None
        gamma, k = (np.ascontiguousarray(hg.gamma[e]), hg.k[e]) if hg else (None, None)

        def force(u: np.ndarray) -> np.ndarray:
            f[:] = 0.0
            uc = np.ascontiguousarray(u, dtype=float)
            for dN, dx, D in rules:
                total_lagrangian_force(uc, conn, dN, dx, D, voigt, f)
            if hg is not None:
                add_hourglass_force(gamma, k, conn, uc, 1.0, f)
            return f
        return force

    @property
    def viscous_hourglass(self) -> bool:
        return self.hg is not None and self.hg.form == "viscous"

    def hourglass_damping(self) -> sp.csr_matrix:
        """(ndof, ndof) kg/s: the viscous hourglass form's damping matrix (with that form)."""
        return self._assemble(self.hg.damping(self.dim))

    def _assemble(self, me: np.ndarray, elements: np.ndarray | None = None) -> sp.csr_matrix:
        """(ndof, ndof): the element matrices me (k, n_loc dim, n_loc dim) summed on the DOFs of
        ``elements`` (k,) (default: every element)."""
        ed = self._edofs if elements is None else self._edofs[elements]
        r, c = np.repeat(ed, ed.shape[1], axis=1).ravel(), np.tile(ed, (1, ed.shape[1])).ravel()
        return sp.csr_matrix((me.ravel(), (r, c)), shape=(self.ndof, self.ndof))

    def add_hourglass_viscous_force(self, v: np.ndarray, out: np.ndarray) -> None:
        """out (n_nodes, dim) N += the viscous hourglass form's force at velocity v, if that form."""
        if self.viscous_hourglass:
            add_hourglass_force(self.hg.gamma, self.hg.c, self._conn, np.ascontiguousarray(v, float), 1.0, out)

    def strain_energy(self, u: np.ndarray) -> float:
        """Stored elastic energy (J) at displacement u (n_nodes, dim) m."""
        if self.formulation == "linear":
            x = u.ravel()
            return 0.5 * float(x @ (self.K @ x))
        energy = self._total_lagrangian_pass(u)[0]
        if self.hg is not None and self.hg.form == "stiffness":
            energy += 0.5 * float(np.vdot(self.hg.force(self.hg.k, u[self.mesh.t.T]), u[self.mesh.t.T]))
        return energy

    def element_strain_energy(self, u: np.ndarray) -> np.ndarray:
        """(nel,) J, small-strain energy 0.5 u_e . k_e u_e of each element."""
        ue = u.ravel()[self._edofs]
        return 0.5 * np.einsum("ea,eab,eb->e", ue, self.ke, ue)

    def inverted_elements(self, u: np.ndarray) -> np.ndarray:
        """Indices of elements whose deformation gradient has det F <= 0 at a quadrature point
        (the element turned inside out)."""
        uc = np.ascontiguousarray(u, dtype=float)
        if getattr(self, "_det_min", None) is None or len(self._det_min) != self.n_elements:
            self._det_min = np.empty(self.n_elements)  # (the guard runs at every sample)
        self._det_min[:] = np.inf
        for q in self.rules:
            smallest_det_F(uc, self._conn, q.dN, self._det_min)
        return np.flatnonzero(self._det_min <= 0.0)

    def _total_lagrangian_pass(self, u: np.ndarray) -> tuple[float, np.ndarray]:
        """(St Venant-Kirchhoff strain energy J, each element's smallest det F (nel,)) at
        u (n_nodes, dim) m, in one compiled pass per quadrature rule."""
        uc = np.ascontiguousarray(u, dtype=float)
        voigt = VOIGT_2D if self.dim == 2 else VOIGT_3D
        det_min = np.full(self.n_elements, np.inf)
        energy = sum(total_lagrangian_energy(uc, self._conn, q.dN, q.dx, Dq, voigt, det_min)
                     for q, Dq in zip(self.rules, self._D_rules))
        return float(energy), det_min

    def centroid_B(self) -> tuple[np.ndarray, np.ndarray]:
        """(small-strain B at each element's centroid (nel, ns, nd) 1/m, its DOFs (nel, nd)):
        the centroid strain is B[e] @ u.ravel()[dofs[e]]."""
        if not hasattr(self, "_B1"):
            q = _quadrature(self.mesh, self.etype, self.etype.one_point_rule(), 1.0, [])
            self._B1 = strain_displacement(q.dN)[:, 0]
        return self._B1, self._edofs

    def centroid_strain_stress(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Small-strain (nel, ns) strain and stress (Pa) at element centroids (Voigt)."""
        B, dofs = self.centroid_B()
        eps = np.einsum("esa,ea->es", B, u.ravel()[dofs])
        return eps, np.einsum("est,et->es", self.D, eps)

    def nodes_where(self, predicate) -> np.ndarray:
        """Indices of nodes whose reference coordinates (dim, n) satisfy ``predicate``."""
        return np.flatnonzero(predicate(self.mesh.p))
