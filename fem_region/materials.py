"""Linear elastic constitutive matrices: isotropic, orthotropic plies, laminates.

Voigt order in 3D: [xx, yy, zz, yz, xz, xy] with engineering shear strains; in 2D:
[xx, yy, xy]. Global axes: x along the beam / plate; in 2D y is the thickness direction and
z the out-of-plane width; in 3D z is the thickness direction. Ply axes: 1 fibre, 2 in-ply
transverse, 3 ply normal. All moduli in Pa.
"""
from __future__ import annotations

import re

import numpy as np

_VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def isotropic(E: float, nu: float) -> np.ndarray:
    """(6, 6) stiffness of an isotropic solid."""
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    C = np.zeros((6, 6))
    C[:3, :3] = lam
    C[np.arange(3), np.arange(3)] += 2 * mu
    C[np.arange(3, 6), np.arange(3, 6)] = mu
    return C


def orthotropic(E1, E2, E3, nu12, nu13, nu23, G12, G13, G23) -> np.ndarray:
    """(6, 6) stiffness in ply axes, by inverting the compliance; raises if not positive definite."""
    S = np.zeros((6, 6))
    S[0, 0], S[1, 1], S[2, 2] = 1 / E1, 1 / E2, 1 / E3
    S[0, 1] = S[1, 0] = -nu12 / E1
    S[0, 2] = S[2, 0] = -nu13 / E1
    S[1, 2] = S[2, 1] = -nu23 / E2
    S[3, 3], S[4, 4], S[5, 5] = 1 / G23, 1 / G13, 1 / G12
    if np.linalg.eigvalsh(S).min() <= 0:
        raise ValueError("orthotropic constants give a compliance that is not positive definite")
    return np.linalg.inv(S)


def transversely_isotropic(E11, E22, nu12, nu23, G12) -> np.ndarray:
    """(6, 6) ply stiffness with isotropy in the 2-3 plane (G23 = E22 / (2 (1 + nu23)))."""
    return orthotropic(E11, E22, E22, nu12, nu12, nu23, G12, G12, E22 / (2 * (1 + nu23)))


def _tensor(C: np.ndarray) -> np.ndarray:
    T = np.zeros((3, 3, 3, 3))
    for I, (i, j) in enumerate(_VOIGT):
        for J, (k, l) in enumerate(_VOIGT):
            for a, b in {(i, j), (j, i)}:
                for c, d in {(k, l), (l, k)}:
                    T[a, b, c, d] = C[I, J]
    return T


def rotate(C: np.ndarray, R: np.ndarray) -> np.ndarray:
    """C (6, 6) given in axes whose unit vectors are the columns of R (3, 3) -> global axes."""
    T = np.einsum("ia,jb,kc,ld,abcd->ijkl", R, R, R, R, _tensor(C))
    return np.array([[T[i, j, k, l] for (k, l) in _VOIGT] for (i, j) in _VOIGT])


def ply_axes(angle_deg: float, dim: int) -> np.ndarray:
    """(3, 3) columns = fibre, in-ply transverse, ply normal, in global axes.

    The ply normal is global y in 2D (so a 90 degree ply has fibres out of the plane) and
    global z in 3D; the fibre angle turns about the normal, measured from x.
    """
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    if dim == 2:
        e1, e3 = np.array([c, 0.0, s]), np.array([0.0, 1.0, 0.0])
    else:
        e1, e3 = np.array([c, s, 0.0]), np.array([0.0, 0.0, 1.0])
    return np.column_stack([e1, np.cross(e3, e1), e3])


def plane_strain(C: np.ndarray) -> np.ndarray:
    """(3, 3) [xx, yy, xy] block of C: eps_zz = gamma_yz = gamma_xz = 0."""
    idx = [0, 1, 5]
    return C[np.ix_(idx, idx)]


def plane_stress(C: np.ndarray) -> np.ndarray:
    """(3, 3) reduced stiffness with sigma_zz = tau_yz = tau_xz = 0 (condensed compliance)."""
    idx = [0, 1, 5]
    return np.linalg.inv(np.linalg.inv(C)[np.ix_(idx, idx)])


def reduce(C: np.ndarray, dim: int, hypothesis: str) -> np.ndarray:
    """C (6, 6) -> the (3, 3) plane matrix for ``hypothesis`` in 2D, or C itself in 3D."""
    if dim == 3:
        return C
    return {"plane_strain": plane_strain, "plane_stress": plane_stress}[hypothesis](C)


MAX_PLIES = 10_000  # (a layup is expanded ply by ply: a count of 10^12 would be a list that large)


def parse_layup(text: str) -> list[float]:
    """'[0_6/90_4/0_6]' or '[0/90]s' or '[45/-45]2s' -> one fibre angle (deg) per ply, bottom up.
    Counts and repeats are whole numbers >= 1; angles are finite degrees in [-180, 180]; at most
    MAX_PLIES plies in all."""
    m = re.fullmatch(r"\s*\[([^\]]+)\]\s*(\d*)\s*(s?)\s*", text)
    if not m:
        raise ValueError("expected e.g. '[0_6/90_4/0_6]', '[0/90]s' or '[45/-45]2s' (nothing after it)")
    groups: list[tuple[float, int]] = []
    for group in m.group(1).split("/"):
        angle, sep, count = group.strip().partition("_")
        try:
            a, n = float(angle), int(count) if sep else 1
        except ValueError:
            raise ValueError(f"bad ply group {group.strip()!r}; allowed: ANGLE or ANGLE_COUNT, e.g. 90_4") from None
        if not -180.0 <= a <= 180.0 or n < 1:
            raise ValueError(f"bad ply group {group.strip()!r}; allowed: an angle in [-180, 180] deg and a count >= 1")
        groups.append((a, n))
    repeat = int(m.group(2) or 1)
    if repeat < 1:
        raise ValueError(f"repeat {repeat}: allowed a whole number >= 1")
    total = sum(n for _, n in groups) * repeat * (2 if m.group(3) else 1)
    if total > MAX_PLIES:
        raise ValueError(f"{total} plies; allowed at most {MAX_PLIES}")
    plies = [a for a, n in groups for _ in range(n)] * repeat
    if m.group(3):
        plies += plies[::-1]
    return plies


def voigt_blocks(dim: int) -> tuple[list[int], list[int]]:
    """Indices of the normal and the shear components in the Voigt vector."""
    return ([0, 1], [2]) if dim == 2 else ([0, 1, 2], [3, 4, 5])


def stress_3d(eps: np.ndarray, C: np.ndarray, dim: int, hypothesis: str = "plane_strain") -> np.ndarray:
    """Full (m, 6) stress (Pa) from (m, 3) 2D or (m, 6) 3D Voigt strains and (m, 6, 6) global C."""
    if dim == 3:
        return np.einsum("mst,mt->ms", C, eps)
    idx = [0, 1, 5]
    if hypothesis == "plane_strain":
        e6 = np.zeros(eps.shape[:-1] + (6,))
        e6[..., idx] = eps
        return np.einsum("mst,mt->ms", C, e6)
    s6 = np.zeros(eps.shape[:-1] + (6,))
    s6[..., idx] = np.einsum("mst,mt->ms", np.array([plane_stress(c) for c in C]), eps)
    return s6
