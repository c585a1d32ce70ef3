"""Hourglass control for one-point (reduced) integration of Q4 and Hex8 (Flanagan & Belytschko 1981).

One-point quadrature leaves the nodal patterns of the bilinear / trilinear monomials
(xi eta in 2D; xi eta, eta zeta, zeta xi, xi eta zeta in 3D) without stiffness. Their
base vectors h are projected against linear fields, gamma = h - (h . x_i) b_i with b the
centroid gradients, so the control force f = k gamma (gamma . u) (stiffness form) or
c gamma (gamma . v) (viscous form) does no work on rigid motion or uniform strain and the
patch test still passes.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

FORMS = ("stiffness", "viscous", "none")


def base_vectors(ref_nodes: np.ndarray) -> np.ndarray:
    """(n_modes, n_loc) hourglass base vectors from reference node coordinates (n_loc, dim) in [0, 1]."""
    s = 2.0 * ref_nodes - 1.0  # -> [-1, 1]
    dim = s.shape[1]
    modes = [np.prod(s[:, list(c)], axis=1) for k in range(2, dim + 1) for c in combinations(range(dim), k)]
    return np.array(modes)


@dataclass
class HourglassControl:
    """Per-element hourglass data.

    gamma: (nel, n_modes, n_loc) -; k: (nel,) N/m stiffness coefficient; c: (nel,) kg/s
    viscous coefficient; form: "stiffness" | "viscous" | "none"; k_ref: (nel,) N/m, the
    stiffness coefficient of kappa whatever the form (to measure hourglass deformation).
    """

    gamma: np.ndarray
    k: np.ndarray
    c: np.ndarray
    form: str
    k_ref: np.ndarray | None = None

    @classmethod
    def build(cls, X_e: np.ndarray, b: np.ndarray, vol: np.ndarray, D: np.ndarray, rho: np.ndarray,
              ref_nodes: np.ndarray, form: str, kappa: float) -> "HourglassControl":
        """X_e: (nel, n_loc, dim) m nodal coordinates; b: (nel, n_loc, dim) 1/m centroid
        gradients; vol: (nel,) m^3 (thickness included in 2D); D: (nel, ns, ns) Pa; rho: (nel,)."""
        if form not in FORMS:
            raise ValueError(f"hourglass form {form!r}: allowed {FORMS}")
        h = base_vectors(ref_nodes)  # (m, nloc)
        hx = np.einsum("ma,eai->emi", h, X_e)
        gamma = h[None] - np.einsum("emi,eai->ema", hx, b)
        bb = np.einsum("eai,eai->e", b, b)
        cmax = np.einsum("eii->ei", D)[:, : b.shape[2]].max(axis=1)  # largest normal stiffness
        k = k_ref = kappa * cmax * vol * bb / gamma.shape[1]
        c = kappa * rho * np.sqrt(cmax / rho) * vol * np.sqrt(bb) / gamma.shape[1]
        if form != "stiffness":
            k = np.zeros_like(k)
        if form != "viscous":
            c = np.zeros_like(c)
        return cls(gamma, k, c, form, k_ref)

    def stiffness(self, dim: int) -> np.ndarray:
        """(nel, n_loc*dim, n_loc*dim) N/m element hourglass stiffness."""
        return self._matrices(self.k, dim)

    def damping(self, dim: int) -> np.ndarray:
        """(nel, n_loc*dim, n_loc*dim) kg/s element damping of the viscous form."""
        return self._matrices(self.c, dim)

    def _matrices(self, coef: np.ndarray, dim: int) -> np.ndarray:
        g = np.einsum("e,ema,emb->eab", coef, self.gamma, self.gamma)
        return np.einsum("eab,ij->eaibj", g, np.eye(dim)).reshape(len(g), g.shape[1] * dim, -1)

    def energy(self, ue: np.ndarray) -> float:
        """Stored hourglass energy (J) of the stiffness form at element displacements ue."""
        q = np.einsum("ema,eai->emi", self.gamma, ue)
        return 0.5 * float(np.einsum("e,emi,emi->", self.k, q, q))

    def indicator(self, ue: np.ndarray) -> float:
        """J: the energy a stiffness control of coefficient kappa would store in the present
        hourglass deformation, for any form (with "none" or "viscous" nothing resists it)."""
        q = np.einsum("ema,eai->emi", self.gamma, ue)
        return 0.5 * float(np.einsum("e,emi,emi->", self.k_ref, q, q))

    def force(self, coef: np.ndarray, ue: np.ndarray) -> np.ndarray:
        """coef (nel,), ue: (nel, n_loc, dim) -> element forces (nel, n_loc, dim)."""
        q = np.einsum("ema,eai->emi", self.gamma, ue)
        return np.einsum("e,ema,emi->eai", coef, self.gamma, q)
