"""From continuum constants to bond parameters.

Closed forms for regular lattices (used directly and as starting values of the inverse
calibration): a triangular (hexagonal) lattice of spacing d = 2r joined by central springs
kn behaves, for uniform strain, as an isotropic plane-stress solid with
E = 2 kn / (sqrt(3) t) and nu = 1/3 (t: layer thickness, here t = 2r), and carries
mass rho * (sqrt(3) / 2) d^2 t per particle. A square lattice with axial springs k1 and
diagonal springs k2 = k1 / 2 is isotropic too: C11 = (k1 + k2) / t, C12 = C66 = k2 / t, so
nu = 1/3 and E = 4 k1 / (3 t).
"""
from __future__ import annotations

import numpy as np


def hexagonal_kn(E: float, radius: float) -> float:
    """Normal bond stiffness (N/m) of a quasi-2D hexagonal layer (t = 2r) with modulus E (Pa)."""
    return np.sqrt(3.0) * radius * E


def hexagonal_modulus(kn: float, radius: float) -> float:
    """Plane-stress modulus (Pa) of a hexagonal layer of bonds kn (N/m), thickness 2r."""
    return 2.0 * kn / (np.sqrt(3.0) * 2.0 * radius)


def hexagonal_density(rho: float) -> float:
    """Sphere density (kg/m^3) that gives a hexagonal layer (t = 2r) the continuum density rho."""
    return rho * 3.0 * np.sqrt(3.0) / np.pi


def square_kn(E: float, radius: float) -> tuple[float, float]:
    """(axial, diagonal) bond stiffness (N/m) of an isotropic square layer (t = 2r) of modulus E."""
    k1 = 0.75 * E * 2.0 * radius
    return k1, 0.5 * k1


def square_density(rho: float) -> float:
    """Sphere density giving a square layer (t = 2r, area (2r)^2 per particle) density rho."""
    return rho * 8.0 / (4.0 / 3.0 * np.pi)
