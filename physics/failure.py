"""Failure indices evaluated on element stresses (index >= 1: the criterion is met).

Stresses are (m, 6) Voigt [xx, yy, zz, yz, xz, xy] in Pa. ``to_ply_axes`` turns global
stresses into ply axes (1 fibre, 2 in-ply transverse, 3 ply normal).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_PAIRS = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def _tensor(s: np.ndarray) -> np.ndarray:
    T = np.empty(s.shape[:-1] + (3, 3))
    for k, (i, j) in enumerate(_PAIRS):
        T[..., i, j] = T[..., j, i] = s[..., k]
    return T


def to_ply_axes(stress: np.ndarray, R: np.ndarray) -> np.ndarray:
    """stress (m, 6) global, R (m, 3, 3) or (3, 3) columns = ply axes -> (m, 6) in ply axes."""
    T = np.swapaxes(R, -1, -2) @ _tensor(stress) @ R  # R^T S R (a three-operand einsum took 5 x as long)
    return np.stack([T[..., i, j] for i, j in _PAIRS], axis=-1)


def hashin_interlaminar(stress_ply: np.ndarray, Z0: float, R0: float) -> np.ndarray:
    """Quadratic delamination initiation (seed paper eq. 13) in ply axes (normal = 3):
    (max(S33, 0) / Z0)^2 + (S13^2 + S23^2) / R0^2; compression does not open a delamination."""
    s33 = np.maximum(stress_ply[..., 2], 0.0)
    return (s33 / Z0) ** 2 + (stress_ply[..., 3] ** 2 + stress_ply[..., 4] ** 2) / R0**2


@dataclass(frozen=True)
class HoffmanStrengths:
    """Nine strengths (Pa, all positive): tension / compression along 1, 2, 3 and shear 23, 13, 12."""

    Xt: float
    Xc: float
    Yt: float
    Yc: float
    Zt: float
    Zc: float
    S23: float
    S13: float
    S12: float


def hoffman(stress_ply: np.ndarray, k: HoffmanStrengths) -> np.ndarray:
    """Orthotropic Hoffman (1967) index in ply axes; uniaxial stress at a strength gives 1."""
    s1, s2, s3, t23, t13, t12 = np.moveaxis(stress_ply, -1, 0)
    X, Y, Z = 1 / (k.Xt * k.Xc), 1 / (k.Yt * k.Yc), 1 / (k.Zt * k.Zc)
    return (0.5 * (Y + Z - X) * (s2 - s3) ** 2 + 0.5 * (Z + X - Y) * (s3 - s1) ** 2
            + 0.5 * (X + Y - Z) * (s1 - s2) ** 2
            + (1 / k.Xt - 1 / k.Xc) * s1 + (1 / k.Yt - 1 / k.Yc) * s2 + (1 / k.Zt - 1 / k.Zc) * s3
            + (t23 / k.S23) ** 2 + (t13 / k.S13) ** 2 + (t12 / k.S12) ** 2)
